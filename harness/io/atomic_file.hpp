// Files written whole or not at all: the data goes to a temporary file of this writer's own beside
// PATH (.NAME.<random>.<pid>@<host>.tmp, created exclusively), which is renamed over PATH once
// complete and flushed to disk (rename is atomic), so readers never see a partial file, an
// interrupted or failed write leaves the previous PATH, and two writers of one PATH never touch
// each other's data (the last rename wins, whole). The guard removes its temporary file on every
// path that does not commit (an exception from the writer, a failed write, flush, close or
// rename); one left by a killed writer is removed by the next writer of PATH once the process that
// made it is gone (remove_stale_temporaries).
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
  std::string path;  // the file the user asked for (not a temporary file, not a run file beside it)
  int err;           // the errno
};

// An errno in words: "no space left on device", "file too large", "read-only file system".
std::string errno_text(int err);

// Bytes reach the temporary file in write calls of at most this many: a file of S bytes takes
// ceil(S / write_chunk) writes and one fsync (the counts io_fault.hpp's hook goes by).
constexpr std::size_t write_chunk = 16384;

class TmpFile {
 public:
  // Creates this writer's temporary file for PATH, after removing those of writers that are gone
  // (unless `locked`: the caller holds PATH's lock and cleans up itself, recorder.cpp). Messages
  // and WriteError::path name `shown` (default PATH): the file the user asked for, when PATH is a
  // part of it (a run file of a results file). Throws WriteError.
  explicit TmpFile(std::string path, std::string shown = "", bool locked = false);
  ~TmpFile();  // closes and removes the temporary file unless committed
  TmpFile(const TmpFile&) = delete;
  TmpFile& operator=(const TmpFile&) = delete;
  const std::string& path() const { return tmp_; }
  const std::string& target() const { return path_; }
  // Appends n bytes. Throws WriteError.
  void write(const void* data, std::size_t n);
  // Appends what `body` prints to a stdio stream over this file. Throws WriteError.
  void write_text(const std::function<void(std::FILE*)>& body);
  // Writes what is pending, flushes the temporary file to disk and closes it (no more writes). Throws WriteError.
  void finish();
  // finish(), then renames the temporary file over PATH and flushes the folder. Throws WriteError
  // (the temporary file is then removed, PATH left as it was).
  void commit();
  // finish(), then gives the file the name PATH only if no file has it (link(2): never replaces
  // one, even when two writers race for a name; a rename where the file system has no hard links)
  // and flushes the folder. Returns false, keeping the temporary file, when PATH exists. Throws
  // WriteError as commit().
  bool commit_new();

 private:
  void put(const char* data, std::size_t n);  // one write call (a chunk), retried while partial
  [[noreturn]] void fail(const std::string& verb, int err);
  std::string path_, shown_, tmp_;
  int fd_ = -1;
  std::string pending_;  // less than write_chunk bytes not yet written
  bool committed_ = false;
};

// "<pid>@<host>" of this process (the host's '.' and '/' as '_'): who made a temporary file.
std::string writer_tag();
// 8 random hex digits: names no other writer picks.
std::string random_hex8();

// Creates PATH's folder if it is missing (errors are left to the write that follows).
void make_parent(const std::string& path);
// Whether `name` (a file name, no folder) is a temporary file of a TmpFile for a file named `target`.
bool is_temporary_of(const std::string& name, const std::string& target);
// Removes the temporary files of PATH left by writers that are gone: those made on this host by a
// process that no longer runs; with `all`, every one (the caller holds PATH's lock, file_lock.hpp,
// under which alone they are made, so none is in use).
void remove_stale_temporaries(const std::string& path, bool all = false);
// Writes a text file through a temporary file (written by `body`, checked, renamed over PATH). Throws WriteError.
void write_text_atomically(const std::string& path, const std::function<void(std::FILE*)>& body);
// Writes n bytes as PATH through a temporary file. Throws WriteError.
void write_file_atomically(const std::string& path, const void* data, std::size_t n);

}  // namespace xb
