// The one writer of every file vtb writes: all or nothing, and an IoError (not bad input)
// naming the path when the folder or the disk refuses.
#include "support/fresh_dir.hh"
#include "vtb/base/atomic_file.hh"

#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

namespace vtb {
namespace {

bool any_part_file(const std::filesystem::path& dir) {
  for (const auto& e : std::filesystem::recursive_directory_iterator(dir))
    if (e.path().string().find(".part") != std::string::npos) return true;
  return false;
}

TEST(AtomicFile, WritesWholeFilesIntoNewFolders) {
  const test::FreshDir dir;
  write_file_atomically(dir / "a/b/one.txt", [](std::ostream& f) { f << "one"; });
  write_files_atomically(dir / "c", {{"x.csv", "1"}, {"y.csv", "2"}});
  EXPECT_EQ(test::read_text(dir / "a/b/one.txt"), "one");
  EXPECT_EQ(test::read_text(dir / "c/x.csv"), "1");
  EXPECT_EQ(test::read_text(dir / "c/y.csv"), "2");
  EXPECT_FALSE(any_part_file(dir.path()));
}

TEST(AtomicFile, AFailedWriterLeavesNothingAndKeepsTheOldFile) {
  const test::FreshDir dir;
  write_file_atomically(dir / "f.txt", [](std::ostream& f) { f << "old"; });
  EXPECT_THROW(write_file_atomically(dir / "f.txt",
                                     [](std::ostream& f) {
                                       f << "half";
                                       throw std::runtime_error("writer failed midway");
                                     }),
               std::runtime_error);
  EXPECT_EQ(test::read_text(dir / "f.txt"), "old") << "a reader never sees half a file";
  EXPECT_THROW(commit_file_atomically(dir / "g.png",
                                      [](const std::filesystem::path& tmp) {
                                        std::ofstream(tmp) << "partial";
                                        return false; // the library said it failed
                                      }),
               IoError);
  EXPECT_FALSE(std::filesystem::exists(dir / "g.png"));
  EXPECT_FALSE(any_part_file(dir.path()));
}

TEST(AtomicFile, AnUnwritableFolderIsAnIoErrorNamingIt) {
  const test::FreshDir dir;
  std::ofstream(dir / "file") << "x"; // a regular file where a folder would have to be
  try {
    write_files_atomically(dir / "file/out", {{"probes.csv", "t\n"}});
    FAIL() << "wrote under a regular file";
  } catch (const IoError& e) {
    EXPECT_EQ(std::string(e.what()).rfind((dir / "file/out").string() + ": cannot create the folder", 0), 0u)
        << e.what();
  }
  EXPECT_THROW(write_file_atomically(dir / "file/x.vtu", [](std::ostream&) {}), IoError);
}

} // namespace
} // namespace vtb
