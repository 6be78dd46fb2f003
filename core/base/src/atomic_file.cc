#include "vtb/base/atomic_file.hh"

#include <cerrno>
#include <cstring>
#include <fstream>

namespace vtb {
namespace {

std::filesystem::path part_of(const std::filesystem::path& file) {
  return file.string() + ".part";
}

[[noreturn]] void fail(const std::filesystem::path& file, const std::string& why) {
  throw IoError(file.string() + ": cannot write: " + why);
}

void rename_or_fail(const std::filesystem::path& tmp, const std::filesystem::path& file) {
  std::error_code ec;
  std::filesystem::rename(tmp, file, ec);
  if (ec) {
    std::filesystem::remove(tmp, ec);
    fail(file, ec.message());
  }
}

} // namespace

void ensure_directory(const std::filesystem::path& dir) {
  if (dir.empty()) return;
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec || !std::filesystem::is_directory(dir))
    throw IoError(dir.string() + ": cannot create the folder: " + (ec ? ec.message() : "a file is in the way"));
}

void write_file_atomically(const std::filesystem::path& file, const std::function<void(std::ostream&)>& fill) {
  ensure_directory(file.parent_path());
  const auto tmp = part_of(file);
  {
    std::ofstream f(tmp, std::ios::binary | std::ios::trunc);
    if (!f) fail(file, std::strerror(errno));
    try {
      fill(f);
    } catch (...) {
      f.close();
      std::error_code ec;
      std::filesystem::remove(tmp, ec);
      throw;
    }
    f.flush();
    if (!f) {
      const std::string why = std::strerror(errno);
      f.close();
      std::error_code ec;
      std::filesystem::remove(tmp, ec);
      fail(file, why);
    }
  }
  rename_or_fail(tmp, file);
}

void commit_file_atomically(const std::filesystem::path& file,
                            const std::function<bool(const std::filesystem::path&)>& make) {
  ensure_directory(file.parent_path());
  const auto tmp = part_of(file);
  bool ok = false;
  std::string why = "the writer failed";
  try {
    ok = make(tmp);
  } catch (const std::exception& e) {
    why = e.what();
  }
  if (!ok) {
    std::error_code ec;
    std::filesystem::remove(tmp, ec);
    fail(file, why);
  }
  rename_or_fail(tmp, file);
}

void write_files_atomically(const std::filesystem::path& dir,
                            const std::vector<std::pair<std::string, std::string>>& files) {
  ensure_directory(dir);
  const auto remove_parts = [&] {
    std::error_code ec;
    for (const auto& [name, text] : files) std::filesystem::remove(part_of(dir / name), ec);
  };
  for (const auto& [name, text] : files) {
    std::ofstream f(part_of(dir / name), std::ios::binary | std::ios::trunc);
    if (f) f << text << std::flush;
    if (!f) {
      const std::string why = std::strerror(errno);
      remove_parts();
      fail(dir / name, why);
    }
  }
  for (const auto& [name, text] : files) {
    std::error_code ec;
    std::filesystem::rename(part_of(dir / name), dir / name, ec);
    if (ec) {
      remove_parts();
      fail(dir / name, ec.message());
    }
  }
}

} // namespace vtb
