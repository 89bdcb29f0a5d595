// Advisory locks between the writers (and readers) of one results file, on a lock file beside it
// (recorder.hpp). Linux open-file-description locks (fcntl F_OFD_SETLK): held by one open of the
// file, so two threads of a process exclude each other as two processes do; released when the
// holder closes it or dies (SIGKILL included: no stale lock to clean); honoured over NFS too.
#pragma once

#include <string>

namespace xb {

class FileLock {
 public:
  enum class Kind { shared, exclusive };
  FileLock() = default;
  // Waits for the lock on `lock_path`; a wait of more than half a second is said once on stderr
  // ("waiting for <shown>: another writer holds it ..."). exclusive: the lock file (and its
  // folder) is made when missing, and a failure is a WriteError naming `shown`, the file the user
  // asked for. shared: without a lock file that can be opened (a packed file, a read-only copy)
  // nothing is held (nothing writes there either).
  FileLock(const std::string& lock_path, Kind kind, const std::string& shown);
  ~FileLock();
  FileLock(FileLock&& o) noexcept;
  FileLock& operator=(FileLock&& o) noexcept;
  FileLock(const FileLock&) = delete;
  FileLock& operator=(const FileLock&) = delete;
  bool held() const { return fd_ >= 0; }

 private:
  int fd_ = -1;
};

}  // namespace xb
