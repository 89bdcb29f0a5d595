#include "file_lock.hpp"

#include "atomic_file.hpp"

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

// One try (F_OFD_SETLK) or a wait (F_OFD_SETLKW) for a lock on the whole file.
Try lock(int fd, FileLock::Kind kind, bool wait) {
  struct flock fl {};
  fl.l_type = kind == FileLock::Kind::exclusive ? F_WRLCK : F_RDLCK;
  fl.l_whence = SEEK_SET;  // l_start = l_len = 0: the whole file; l_pid must be 0 for OFD locks
  for (;;) {
    if (::fcntl(fd, wait ? F_OFD_SETLKW : F_OFD_SETLK, &fl) == 0) return Try::held;
    if (errno == EINTR) continue;
    return errno == EAGAIN || errno == EACCES ? Try::busy : Try::unsupported;
  }
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

}  // namespace xb
