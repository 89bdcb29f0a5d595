#include "file_lock.hpp"

#include "atomic_file.hpp"

#include "../../core/error.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <filesystem>
#include <iostream>
#include <thread>
#include <utility>

namespace fs = std::filesystem;

namespace xb {

namespace {
enum class Try { held, busy, unsupported };

// One try (F_OFD_SETLK) or a wait (F_OFD_SETLKW) for a lock on the whole file (len 0), or on
// bytes [start, start + len).
Try lock(int fd, FileLock::Kind kind, bool wait, off_t start = 0, off_t len = 0) {
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
  // A file system without locks: go on unlocked rather than never.
  if (lock(fd_, kind, false) != Try::busy) return;
  // Another process holds it: poll quietly for a moment (an append takes milliseconds), then say so.
  const auto start = std::chrono::steady_clock::now();
  while (std::chrono::steady_clock::now() - start < std::chrono::milliseconds(500)) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
    if (lock(fd_, kind, false) != Try::busy) return;
  }
  std::cerr << "xpbd-bench: waiting for " << shown << ": another writer holds it ...\n" << std::flush;
  lock(fd_, kind, true);
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
  lock(fd_, FileLock::Kind::shared, true, 1, 1);  // in use
}

SharedCounter::~SharedCounter() {
  if (fd_ >= 0) ::close(fd_);
}

long SharedCounter::next() {
  lock(fd_, FileLock::Kind::exclusive, true, 0, 1);
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
