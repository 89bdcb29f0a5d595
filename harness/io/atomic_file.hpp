// Files written whole or not at all: the data goes to PATH.tmp, which is renamed over PATH once
// complete (rename is atomic), so readers never see a partial file and an interrupted write leaves
// the previous PATH. The guard removes PATH.tmp on every path that does not commit (an exception
// from the writer, a failed rename).
#pragma once

#include <cstdio>
#include <functional>
#include <string>

namespace xb {

class TmpFile {
 public:
  explicit TmpFile(std::string path);  // removes a stale PATH.tmp
  ~TmpFile();                          // removes PATH.tmp unless committed
  TmpFile(const TmpFile&) = delete;
  TmpFile& operator=(const TmpFile&) = delete;
  const std::string& path() const { return tmp_; }
  // Flushes PATH.tmp to disk, renames it over PATH and flushes the folder. Throws xb::Error.
  void commit();

 private:
  std::string path_, tmp_;
  bool committed_ = false;
};

// Creates PATH's folder if it is missing (errors are left to the write that follows).
void make_parent(const std::string& path);
// Writes a text file through PATH.tmp (written by `body`, checked, renamed over PATH). Throws xb::Error.
void write_text_atomically(const std::string& path, const std::function<void(std::FILE*)>& body);

}  // namespace xb
