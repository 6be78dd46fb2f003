#include "vtb/meshes/msh_io.hh"

#include "vtb/meshes/atomic_file.hh"

#include "vtb/meshes/input_error.hh"
#include "vtb/meshes/mesh_serialize.hh"
#include "vtb/meshes/module.hh"
#include "vtb/meshes/msh_prescan.hh"

#include "gmsh_backend.hh"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstring>
#include <fstream>
#include <iostream>
#include <sstream>

namespace vtb {
namespace {

/// The gmsh module (gmsh_backend.hh), loaded by the reader's child or for a write.
class GmshModule {
public:
  GmshModule() : m_module("vtb_gmsh_backend.so", VTB_GMSH_BACKEND, "vtb's gmsh module") {}
  template <class Fn> Fn* function(const char* name) const {
    auto* f = reinterpret_cast<Fn*>(m_module.symbol(name));
    if (f == nullptr) throw IoError(std::string("vtb's gmsh module (vtb_gmsh_backend.so) has no ") + name);
    return f;
  }

private:
  Module m_module;
};

/// The reader process: reads the file, writes "M" + the serialized mesh or "E" + the error to
/// the pipe, and exits; a fault kills it plainly (the parent turns the signal into a refusal).
[[noreturn]] void run_reader_child(const std::string& src, int out_fd) {
  // The child dies plainly on a fault: no sanitizer or fuzzer report, no core dump; the
  // parent turns the signal into a refusal.
  for (int sig : {SIGSEGV, SIGBUS, SIGABRT, SIGFPE, SIGILL}) std::signal(sig, SIG_DFL);
  // What a failing reader prints (glibc's "double free", gmsh's messages) is not for the
  // user: the parent reports one line.
  if (const int null = open("/dev/null", O_WRONLY); null >= 0) {
    dup2(null, STDOUT_FILENO);
    dup2(null, STDERR_FILENO);
    close(null);
  }
  std::string out;
  try {
    GmshModule().function<gmsh_backend::ReadFn>(gmsh_backend::kRead)(src.c_str(), &out);
  } catch (const std::exception& e) {
    out = std::string("E") + e.what();
  }
  for (std::size_t done = 0; done < out.size();) {
    const ssize_t w = write(out_fd, out.data() + done, out.size() - done);
    if (w <= 0) _exit(3);
    done += static_cast<std::size_t>(w);
  }
  _exit(0);
}

/// Everything the reader writes before it exits or the deadline passes; `timed_out` says which.
std::string read_until(int fd, std::chrono::steady_clock::time_point deadline, bool& timed_out) {
  timed_out = false;
  std::string data;
  char buf[1 << 16];
  for (;;) {
    const auto left =
        std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0) {
      timed_out = true;
      break;
    }
    pollfd p{fd, POLLIN, 0};
    const int r = poll(&p, 1, static_cast<int>(left.count()));
    if (r < 0 && errno == EINTR) continue;
    if (r == 0) {
      timed_out = true;
      break;
    }
    const ssize_t n = read(fd, buf, sizeof buf);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    data.append(buf, static_cast<std::size_t>(n));
  }
  return data;
}

AnyMesh read_msh_isolated(const std::string& src, std::chrono::seconds limit) {
  int fds[2];
  if (pipe(fds) != 0) throw InputError(src + ": cannot create a pipe for the mesh reader");
  std::cout.flush();
  std::cerr.flush();
  const pid_t pid = fork();
  if (pid < 0) {
    close(fds[0]);
    close(fds[1]);
    throw InputError(src + ": cannot start the mesh reader");
  }
  if (pid == 0) {
    close(fds[0]);
    run_reader_child(src, fds[1]);
  }
  close(fds[1]);
  bool timed_out = false;
  const std::string data = read_until(fds[0], std::chrono::steady_clock::now() + limit, timed_out);
  close(fds[0]);
  if (timed_out) kill(pid, SIGKILL);
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (timed_out)
    throw InputError(src + ": reading the mesh took longer than " + std::to_string(limit.count()) + " s; refused");
  if (WIFSIGNALED(status))
    throw InputError(src + ": the mesh reader crashed on this file (signal " + std::to_string(WTERMSIG(status)) +
                     "); the file is malformed");
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0 || data.empty())
    throw InputError(src + ": the mesh reader failed on this file");
  if (data[0] == 'E') throw InputError(data.substr(1));
  return deserialize(std::string_view(data).substr(1), src);
}

} // namespace

AnyMesh read_msh(const std::filesystem::path& file) {
  const std::string src = file.string();
  std::error_code ec;
  const auto size = std::filesystem::file_size(file, ec);
  if (ec) throw InputError(src + ": cannot open mesh file");
  if (size > (std::uintmax_t{1} << 30)) throw InputError(src + ": mesh file larger than 1 GiB; refused");
  std::string content;
  {
    std::ifstream in(file, std::ios::binary);
    if (!in) throw InputError(src + ": cannot open mesh file");
    std::ostringstream ss;
    ss << in.rdbuf();
    content = ss.str();
  }
  prescan_msh(content, src);
  AnyMesh mesh = read_msh_isolated(src, std::chrono::seconds(8));
  const int flipped = std::visit([](auto& m) { return check_and_orient(m); }, mesh);
  if (flipped > 0) std::cerr << "vtb: warning: " << src << ": " << flipped << " inverted cells re-oriented\n";
  return mesh;
}

template <int dim> void write_msh(const Mesh<dim>& mesh, const std::filesystem::path& file) {
  // gmsh picks the format from the extension, so the temporary name ends in .msh too.
  const std::filesystem::path tmp = file.parent_path() / ("." + file.filename().string() + ".part.msh");
  ensure_directory(file.parent_path());
  std::string error;
  try {
    const GmshModule gmsh;
    gmsh.function<gmsh_backend::WriteFn<dim>>(gmsh_backend::kWrite<dim>)(&mesh, tmp.c_str(), &error);
  } catch (const IoError& e) {
    error = e.what();
  }
  if (!error.empty()) {
    std::error_code ec;
    std::filesystem::remove(tmp, ec);
    throw IoError(file.string() + ": cannot write: " + error);
  }
  std::error_code ec;
  std::filesystem::rename(tmp, file, ec);
  if (ec) {
    std::filesystem::remove(tmp, ec);
    throw IoError(file.string() + ": cannot write: " + ec.message());
  }
}

template void write_msh<2>(const Mesh<2>&, const std::filesystem::path&);
template void write_msh<3>(const Mesh<3>&, const std::filesystem::path&);

} // namespace vtb
