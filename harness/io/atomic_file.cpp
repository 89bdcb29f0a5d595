#include "atomic_file.hpp"

#include "../../core/error.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <filesystem>

namespace fs = std::filesystem;

namespace xb {

namespace {
void fsync_path(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY);
  if (fd >= 0) {
    ::fsync(fd);
    ::close(fd);
  }
}
}  // namespace

TmpFile::TmpFile(std::string path) : path_(std::move(path)), tmp_(path_ + ".tmp") {
  std::error_code ec;
  fs::remove(tmp_, ec);
}

TmpFile::~TmpFile() {
  if (committed_) return;
  std::error_code ec;
  fs::remove(tmp_, ec);
}

void TmpFile::commit() {
  fsync_path(tmp_);
  std::error_code ec;
  fs::rename(tmp_, path_, ec);
  if (ec) throw Error("cannot rename " + tmp_ + " to " + path_ + ": " + ec.message());
  committed_ = true;
  const fs::path parent = fs::path(path_).parent_path();
  fsync_path(parent.empty() ? "." : parent.string());
}

void make_parent(const std::string& path) {
  const fs::path parent = fs::path(path).parent_path();
  std::error_code ec;
  if (!parent.empty()) fs::create_directories(parent, ec);
}

void write_text_atomically(const std::string& path, const std::function<void(std::FILE*)>& body) {
  make_parent(path);
  TmpFile tmp(path);
  std::FILE* f = std::fopen(tmp.path().c_str(), "w");
  if (!f) throw Error("cannot create " + tmp.path());
  try {
    body(f);
  } catch (...) {
    std::fclose(f);
    throw;
  }
  const bool ok = std::fflush(f) == 0 && !std::ferror(f);
  if (std::fclose(f) != 0 || !ok) throw Error("cannot write " + tmp.path());
  tmp.commit();
}

}  // namespace xb
