// Advisory locks between the writers of one results file, on a lock file in its runs folder
// (recorder.hpp; readers take none). Linux open-file-description locks (fcntl F_OFD_SETLK): held
// by one open of the file, so two threads of a process exclude each other as two processes do;
// released when the holder closes it or dies (SIGKILL included: no stale lock to clean); honoured
// over NFS with lockd. A file system that refuses locks (ENOLCK: NFS without lockd, some
// containers) is an error naming it: nothing is written unlocked.
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
  // nothing is held (nothing writes there either). A lock the file system refuses is a WriteError
  // naming `shown`, the file system and its mount point.
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

// A number that processes (mpirun's ranks, on one machine or many) take in turn, each a different
// one: the next job of a sweep. The file's first 8 bytes hold the next number, read and increased
// under a lock on byte 0; every user holds a shared lock on byte 1 while it works, so that a counter
// file nobody holds (a killed sweep's) is known stale: remove_unused_counter.
class SharedCounter {
 public:
  // Opens (creating it, and its folder, when missing) the counter file. Throws xb::Error (a
  // WriteError where the file system refuses locks).
  explicit SharedCounter(const std::string& path);
  ~SharedCounter();
  SharedCounter(const SharedCounter&) = delete;
  SharedCounter& operator=(const SharedCounter&) = delete;
  // The next number: 0, 1, 2, ... over all users together.
  long next();

 private:
  std::string path_;
  int fd_ = -1;
};
// Removes a counter file that no process uses; true when it did.
bool remove_unused_counter(const std::string& path);

}  // namespace xb
