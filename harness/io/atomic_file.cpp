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

}  // namespace xb
