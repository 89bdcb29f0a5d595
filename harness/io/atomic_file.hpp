// Files written whole or not at all: the data goes to PATH.tmp, which is renamed over PATH once
// complete and flushed to disk (rename is atomic), so readers never see a partial file and an
// interrupted or failed write leaves the previous PATH. The guard removes PATH.tmp on every path
// that does not commit (an exception from the writer, a failed write, flush, close or rename).
//
// Every byte of every output file goes through TmpFile::write, HDF5 files included (they are built
// in memory, h5io.hpp): a full disk is met here, as an errno, and reported as a WriteError naming
// the file and the cause; the test hook of io_fault.hpp fails these calls on demand.
#pragma once

#include "../../core/error.hpp"

#include <cstddef>
#include <cstdio>
#include <functional>
#include <string>
#include <vector>

namespace xb {

// A failed create, write, flush, close or rename of an output file: what() is one line naming the
// file the user asked for and the cause in words, e.g. "cannot write r.h5: no space left on device
// (r.h5 is left as it was)". The Python package raises it as xpbd_bench.WriteError (an OSError).
struct WriteError : Error {
  WriteError(std::string path, int err, const std::string& message) : Error(message), path(std::move(path)), err(err) {}
  std::string path;  // the file being written (not its .tmp)
  int err;           // the errno
};

// An errno in words: "no space left on device", "file too large", "read-only file system".
std::string errno_text(int err);

// Bytes reach PATH.tmp in write calls of at most this many: a file of S bytes takes
// ceil(S / write_chunk) writes and one fsync (the counts io_fault.hpp's hook goes by).
constexpr std::size_t write_chunk = 16384;

class TmpFile {
 public:
  // Removes a stale PATH.tmp and creates it afresh. Throws WriteError.
  explicit TmpFile(std::string path);
  ~TmpFile();  // closes and removes PATH.tmp unless committed
  TmpFile(const TmpFile&) = delete;
  TmpFile& operator=(const TmpFile&) = delete;
  const std::string& path() const { return tmp_; }
  const std::string& target() const { return path_; }
  // Appends n bytes. Throws WriteError.
  void write(const void* data, std::size_t n);
  // Appends what `body` prints to a stdio stream over this file. Throws WriteError.
  void write_text(const std::function<void(std::FILE*)>& body);
  // Writes what is pending, flushes PATH.tmp to disk and closes it (no more writes). Throws WriteError.
  void finish();
  // finish(), then renames PATH.tmp over PATH and flushes the folder. Throws WriteError (PATH.tmp
  // is then removed, PATH left as it was).
  void commit();

 private:
  void put(const char* data, std::size_t n);  // one write call (a chunk), retried while partial
  [[noreturn]] void fail(const std::string& verb, int err);
  std::string path_, tmp_;
  int fd_ = -1;
  std::string pending_;  // less than write_chunk bytes not yet written
  bool committed_ = false;
};

// Creates PATH's folder if it is missing (errors are left to the write that follows).
void make_parent(const std::string& path);
// Writes a text file through PATH.tmp (written by `body`, checked, renamed over PATH). Throws WriteError.
void write_text_atomically(const std::string& path, const std::function<void(std::FILE*)>& body);
// Writes n bytes as PATH through PATH.tmp. Throws WriteError.
void write_file_atomically(const std::string& path, const void* data, std::size_t n);
// The bytes of a file (one that is being appended to). Throws xb::Error naming it and the cause.
std::vector<char> read_file(const std::string& path);

}  // namespace xb
