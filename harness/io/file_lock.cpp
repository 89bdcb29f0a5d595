#include "file_lock.hpp"

#include "atomic_file.hpp"
#include "io_fault.hpp"

#include "../../core/error.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <thread>
#include <utility>

namespace fs = std::filesystem;

namespace xb {

namespace {
enum class Try { held, busy, unsupported };

// One try (F_OFD_SETLK) or a wait (F_OFD_SETLKW) for a lock on the whole file (len 0), or on
// bytes [start, start + len).
Try lock(int fd, FileLock::Kind kind, bool wait, off_t start = 0, off_t len = 0) {
  if (const int e = io_fault::next_lock()) {
    errno = e;
    return Try::unsupported;
  }
  struct flock fl {};
  fl.l_type = kind == FileLock::Kind::exclusive ? F_WRLCK : F_RDLCK;
  fl.l_whence = SEEK_SET;  // l_pid must be 0 for OFD locks
  fl.l_start = start;
  fl.l_len = len;
  for (;;) {
    if (::fcntl(fd, wait ? F_OFD_SETLKW : F_OFD_SETLK, &fl) == 0) return Try::held;
    if (errno == EINTR) continue;
    return errno == EAGAIN || errno == EACCES ? Try::busy : Try::unsupported;
  }
}

// "nfs4 at /mnt/data": the type and mount point of the file system holding `path`, from
// /proc/self/mountinfo (the longest mount point that contains it); "" where unknown.
std::string file_system_of(const std::string& path) {
  std::error_code ec;
  const std::string where = fs::weakly_canonical(fs::absolute(path, ec), ec).string();
  std::ifstream in("/proc/self/mountinfo");
  std::string line, best_point, best_type;
  while (std::getline(in, line)) {
    std::istringstream ls(line);
    std::string id, parent, dev, root, point, field;
    ls >> id >> parent >> dev >> root >> point;
    while (ls >> field && field != "-") {
    }
    std::string type;
    ls >> type;
    const bool inside = where == point || where.starts_with(point == "/" ? point : point + "/");
    if (inside && point.size() >= best_point.size()) best_point = point, best_type = type;
  }
  return best_type.empty() ? "" : best_type + " at " + best_point;
}

// The error of a lock the file system refuses (ENOLCK: NFS without lockd, some containers).
WriteError no_locks(const std::string& lock_path, const std::string& shown, int err) {
  const std::string fsys = file_system_of(lock_path);
  return WriteError(shown, err,
                    "cannot lock " + shown + ": the file system" + (fsys.empty() ? "" : " (" + fsys + ")") +
                        " does not lock files (" + errno_text(err) +
                        "); refusing to write without a lock, as concurrent writers could lose runs (" + shown +
                        " is left as it was): write to a file system that locks (a local disk; NFS with lockd)");
}

void unlock(int fd, off_t start, off_t len) {
  struct flock fl {};
  fl.l_type = F_UNLCK;
  fl.l_whence = SEEK_SET;
  fl.l_start = start;
  fl.l_len = len;
  ::fcntl(fd, F_OFD_SETLK, &fl);
}
}  // namespace

FileLock::FileLock(const std::string& lock_path, Kind kind, const std::string& shown) {
  if (kind == Kind::exclusive) {
    std::error_code ec;
    fs::create_directories(fs::path(lock_path).parent_path(), ec);
    fd_ = ::open(lock_path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0666);
    if (fd_ < 0) {
      const int e = errno;
      throw WriteError(shown, e, "cannot write " + shown + ": " + errno_text(e) + " (" + shown + " is left as it was)");
    }
  } else {
    fd_ = ::open(lock_path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd_ < 0) return;
  }
  // A file system without locks: refused, never a silent write without one.
  const auto refuse = [&] {
    const int e = errno;
    ::close(std::exchange(fd_, -1));
    throw no_locks(lock_path, shown, e);
  };
  Try got = lock(fd_, kind, false);
  // Another process holds it: poll quietly for a moment (an append takes milliseconds), then say so.
  const auto start = std::chrono::steady_clock::now();
  while (got == Try::busy && std::chrono::steady_clock::now() - start < std::chrono::milliseconds(500)) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
    got = lock(fd_, kind, false);
  }
  if (got == Try::busy) {
    std::cerr << "xpbd-bench: waiting for " << shown << ": another writer holds it ...\n" << std::flush;
    got = lock(fd_, kind, true);
  }
  if (got == Try::unsupported) refuse();
}

FileLock::~FileLock() {
  if (fd_ >= 0) ::close(fd_);  // releases the lock
}

FileLock::FileLock(FileLock&& o) noexcept : fd_(std::exchange(o.fd_, -1)) {}

FileLock& FileLock::operator=(FileLock&& o) noexcept {
  if (this != &o) {
    if (fd_ >= 0) ::close(fd_);
    fd_ = std::exchange(o.fd_, -1);
  }
  return *this;
}

SharedCounter::SharedCounter(const std::string& path) : path_(path) {
  std::error_code ec;
  fs::create_directories(fs::path(path).parent_path(), ec);
  fd_ = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0666);
  if (fd_ < 0) throw Error("cannot open " + path + ": " + errno_text(errno));
  if (lock(fd_, FileLock::Kind::shared, true, 1, 1) != Try::held) {  // in use
    const int e = errno;
    ::close(std::exchange(fd_, -1));
    throw no_locks(path, path, e);
  }
}

SharedCounter::~SharedCounter() {
  if (fd_ >= 0) ::close(fd_);
}

long SharedCounter::next() {
  if (lock(fd_, FileLock::Kind::exclusive, true, 0, 1) != Try::held) throw no_locks(path_, path_, errno);
  long long n = 0;
  if (::pread(fd_, &n, sizeof n, 0) != static_cast<ssize_t>(sizeof n)) n = 0;  // a new file: 0
  const long long after = n + 1;
  const bool written = ::pwrite(fd_, &after, sizeof after, 0) == static_cast<ssize_t>(sizeof after);
  unlock(fd_, 0, 1);
  if (!written) throw Error("cannot write " + path_ + ": " + errno_text(errno));
  return static_cast<long>(n);
}

bool remove_unused_counter(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDWR | O_CLOEXEC);
  if (fd < 0) return false;
  const bool unused = lock(fd, FileLock::Kind::exclusive, false, 1, 1) == Try::held;
  if (unused) ::unlink(path.c_str());
  ::close(fd);
  return unused;
}

}  // namespace xb
