#pragma once
/// \file
/// The one way vtb writes a file (docs/architecture.md, conventions): to FILE.part, then renamed, so a
/// reader never sees half a file and a failed write leaves nothing. A failure is an IoError
/// naming the path and the reason (not a bad-input error: the input was fine, the disk or the
/// folder was not); the CLI exits with its own code for it.

#include <filesystem>
#include <functional>
#include <iosfwd>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace vtb {

/// A write that failed: a missing or read-only folder, a full disk. One line naming the path.
class IoError : public std::runtime_error {
public:
  explicit IoError(const std::string& what) : std::runtime_error(what) {}
};

/// Creates `dir` and its parents; IoError naming it when that fails (a parent is a file, no
/// permission, a read-only file system).
void ensure_directory(const std::filesystem::path& dir);

/// Writes `file` through `fill`, which writes the content to a stream; atomically (see above).
void write_file_atomically(const std::filesystem::path& file, const std::function<void(std::ostream&)>& fill);

/// For libraries that write by path (gmsh, stb, deal.II): `make(tmp)` writes the temporary
/// file and returns false (or throws) on failure; then the rename. IoError on failure.
void commit_file_atomically(const std::filesystem::path& file,
                            const std::function<bool(const std::filesystem::path&)>& make);

/// Writes each (name, text) into `dir` (created if needed), all or nothing: every file to
/// NAME.part first, then all renamed; on failure the .part files are removed.
void write_files_atomically(const std::filesystem::path& dir,
                            const std::vector<std::pair<std::string, std::string>>& files);

} // namespace vtb
