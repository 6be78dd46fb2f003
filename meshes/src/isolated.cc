#include "vtb/meshes/isolated.hh"

#include "vtb/base/input_error.hh"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <fstream>
#include <iostream>
#include <sstream>

namespace vtb {

std::string read_untrusted(const std::filesystem::path& file, const std::string& what) {
  const std::string src = file.string();
  std::error_code ec;
  const auto size = std::filesystem::file_size(file, ec);
  if (ec) throw InputError(src + ": cannot open " + what + " file");
  if (size > (std::uintmax_t{1} << 30)) throw InputError(src + ": " + what + " file larger than 1 GiB; refused");
  std::ifstream in(file, std::ios::binary);
  if (!in) throw InputError(src + ": cannot open " + what + " file");
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

namespace {

/// The child: runs the work, writes "R" + its bytes or "E" + the error to the pipe, and exits;
/// a fault kills it plainly (the parent turns the signal into a refusal).
[[noreturn]] void run_child(const std::function<std::string()>& work, int out_fd) {
  // The child dies plainly on a fault: no sanitizer or fuzzer report, no core dump.
  for (int sig : {SIGSEGV, SIGBUS, SIGABRT, SIGFPE, SIGILL}) std::signal(sig, SIG_DFL);
  // What a failing reader prints (glibc's "double free", a library's messages) is not for the
  // user: the parent reports one line.
  if (const int null = open("/dev/null", O_WRONLY); null >= 0) {
    dup2(null, STDOUT_FILENO);
    dup2(null, STDERR_FILENO);
    close(null);
  }
  std::string out;
  try {
    out = "R" + work();
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

/// Everything the child writes before it exits or the deadline passes; `timed_out` says which.
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

} // namespace

std::string run_isolated(const std::string& src, const std::string& what, std::chrono::seconds limit,
                         const std::function<std::string()>& work) {
  int fds[2];
  if (pipe(fds) != 0) throw InputError(src + ": cannot create a pipe for the " + what + " reader");
  std::cout.flush();
  std::cerr.flush();
  const pid_t pid = fork();
  if (pid < 0) {
    close(fds[0]);
    close(fds[1]);
    throw InputError(src + ": cannot start the " + what + " reader");
  }
  if (pid == 0) {
    close(fds[0]);
    run_child(work, fds[1]);
  }
  close(fds[1]);
  bool timed_out = false;
  std::string data = read_until(fds[0], std::chrono::steady_clock::now() + limit, timed_out);
  close(fds[0]);
  if (timed_out) kill(pid, SIGKILL);
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (timed_out)
    throw InputError(src + ": reading the " + what + " took longer than " + std::to_string(limit.count()) +
                     " s; refused");
  if (WIFSIGNALED(status))
    throw InputError(src + ": the " + what + " reader crashed on this file (signal " +
                     std::to_string(WTERMSIG(status)) + "); the file is malformed");
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0 || data.empty())
    throw InputError(src + ": the " + what + " reader failed on this file");
  if (data[0] == 'E') throw InputError(data.substr(1));
  return data.substr(1);
}

} // namespace vtb
