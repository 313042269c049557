#include "output_file.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <climits>
#include <cstdlib>
#include <cstring>

namespace sim {
namespace {

/// What an output path names (symbolic links followed).
enum class OutputKind { kStdout, kNew, kRegular, kStream };

std::string reason() { return std::strerror(errno); }

std::string dir_of(const std::string& p) {
  const auto slash = p.find_last_of('/');
  if (slash == std::string::npos) return ".";
  return slash == 0 ? "/" : p.substr(0, slash);
}
std::string base_of(const std::string& p) {
  const auto slash = p.find_last_of('/');
  return slash == std::string::npos ? p : p.substr(slash + 1);
}

/// The path a regular or new output is written to, and what is there now.
struct Target {
  OutputKind kind = OutputKind::kNew;
  std::string path;  // the file to replace or create (links resolved); the path itself for a stream
  mode_t mode = 0;   // a regular file's permission bits
};

/// Follows a chain of symbolic links whose last target does not exist yet.
bool follow_dangling(std::string p, std::string& out, std::string& err) {
  for (int hops = 0; hops < 40; ++hops) {
    struct stat st;
    if (lstat(p.c_str(), &st) != 0 || !S_ISLNK(st.st_mode)) {
      out = p;
      return true;
    }
    char buf[PATH_MAX];
    const ssize_t n = readlink(p.c_str(), buf, sizeof buf - 1);
    if (n < 0) return err = "cannot write " + p + ": " + reason(), false;
    const std::string to(buf, static_cast<std::size_t>(n));
    p = to.front() == '/' ? to : dir_of(p) + "/" + to;
  }
  return err = "cannot write " + p + ": too many levels of symbolic links", false;
}

bool resolve(const std::string& path, Target& t, std::string& err) {
  if (path.empty()) return err = "an output needs a file name", false;
  if (path == "-") return t.kind = OutputKind::kStdout, true;
  struct stat st;
  if (stat(path.c_str(), &st) == 0) {
    if (S_ISDIR(st.st_mode)) return err = "cannot write " + path + ": it is a directory", false;
    if (!S_ISREG(st.st_mode)) {
      t.kind = OutputKind::kStream;
      t.path = path;
      return true;
    }
    char real[PATH_MAX];
    if (realpath(path.c_str(), real) == nullptr) return err = "cannot write " + path + ": " + reason(), false;
    t.kind = OutputKind::kRegular;
    t.path = real;
    t.mode = st.st_mode & 07777;
    return true;
  }
  if (errno != ENOENT) return err = "cannot write " + path + ": " + reason(), false;
  // Nothing there yet, or a link to nothing yet: the file is created where the chain ends.
  if (!follow_dangling(path, t.path, err)) return false;
  struct stat dst;
  const std::string dir = dir_of(t.path);
  if (stat(dir.c_str(), &dst) != 0 || !S_ISDIR(dst.st_mode))
    return err = "cannot write " + path + ": directory " + dir + " does not exist", false;
  t.kind = OutputKind::kNew;
  return true;
}

/// A temporary file beside `target`, hidden, unique (never a name a user may have: "x.tmp").
int make_temp(const std::string& target, std::string& tmp) {
  tmp = dir_of(target) + "/." + base_of(target) + ".XXXXXX";
  return mkstemp(tmp.data());
}

bool replace_file(const Target& t, const std::string& text, const std::string& shown, std::string& err) {
  std::string tmp;
  const int fd = make_temp(t.path, tmp);
  if (fd < 0) return err = "cannot write " + shown + ": " + reason(), false;
  mode_t mode = t.mode;
  if (t.kind == OutputKind::kNew) {
    const mode_t mask = umask(0);
    umask(mask);
    mode = 0666 & ~mask;
  }
  bool ok = write_all(fd, text, shown, err);
  if (ok && (fsync(fd) != 0 || fchmod(fd, mode) != 0)) ok = false, err = "cannot write " + shown + ": " + reason();
  if (close(fd) != 0 && ok) ok = false, err = "cannot write " + shown + ": " + reason();
  if (ok && rename(tmp.c_str(), t.path.c_str()) != 0) ok = false, err = "cannot write " + shown + ": " + reason();
  if (!ok) unlink(tmp.c_str());
  return ok;
}

bool write_stream(const std::string& path, const std::string& text, std::string& err) {
  const int fd = open(path.c_str(), O_WRONLY | O_NOCTTY | O_CLOEXEC);
  if (fd < 0) return err = "cannot write " + path + ": " + reason(), false;
  bool ok = write_all(fd, text, path, err);
  if (close(fd) != 0 && ok) ok = false, err = "cannot write " + path + ": " + reason();
  return ok;
}

}  // namespace

bool write_all(int fd, const std::string& text, const std::string& name, std::string& err) {
  // A reader that went away is an error here, not a silent death by SIGPIPE.
  struct sigaction ignore {
  }, old{};
  ignore.sa_handler = SIG_IGN;
  sigaction(SIGPIPE, &ignore, &old);
  const char* p = text.data();
  std::size_t left = text.size();
  bool ok = true;
  while (left > 0) {
    const ssize_t n = write(fd, p, left);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      err = "cannot write " + name + ": " + (n < 0 ? reason() : std::string("nothing written"));
      ok = false;
      break;
    }
    p += n;
    left -= static_cast<std::size_t>(n);
  }
  sigaction(SIGPIPE, &old, nullptr);
  return ok;
}

bool check_output(const std::string& path, std::string& err) {
  Target t;
  if (!resolve(path, t, err)) return false;
  switch (t.kind) {
    case OutputKind::kStdout:
      return true;
    case OutputKind::kStream:
      if (access(path.c_str(), W_OK) != 0) return err = "cannot write " + path + ": " + reason(), false;
      return true;
    case OutputKind::kRegular:
      if (access(t.path.c_str(), W_OK) != 0) return err = "cannot write " + path + ": " + reason(), false;
      [[fallthrough]];
    case OutputKind::kNew: {
      std::string tmp;
      const int fd = make_temp(t.path, tmp);
      if (fd < 0)
        return err = "cannot write " + path + ": cannot create a file in " + dir_of(t.path) + " (" + reason() + ")",
               false;
      close(fd);
      unlink(tmp.c_str());
      return true;
    }
  }
  return true;
}

bool write_output(const std::string& path, const std::string& text, std::string& err) {
  Target t;
  if (!resolve(path, t, err)) return false;
  switch (t.kind) {
    case OutputKind::kStdout:
      return write_all(STDOUT_FILENO, text, "standard output", err);
    case OutputKind::kStream:
      return write_stream(path, text, err);
    case OutputKind::kNew:
    case OutputKind::kRegular:
      return replace_file(t, text, path, err);
  }
  return false;
}

bool is_stdout(const std::string& path) {
  if (path == "-") return true;
  struct stat a, b;
  return stat(path.c_str(), &a) == 0 && fstat(STDOUT_FILENO, &b) == 0 && a.st_dev == b.st_dev && a.st_ino == b.st_ino;
}

}  // namespace sim
