#include "atomic_file.hpp"

#include "io_fault.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <filesystem>
#include <mutex>
#include <random>
#include <system_error>
#include <utility>

namespace fs = std::filesystem;

namespace xb {

namespace {
void fsync_folder(const std::string& path) {
  io_fault::durable_step();
  const fs::path parent = fs::path(path).parent_path();
  const int fd = ::open(parent.empty() ? "." : parent.c_str(), O_RDONLY);
  if (fd >= 0) {
    ::fsync(fd);  // the rename is done: a failure here loses only durability, not the file
    ::close(fd);
  }
}

// A file system that has no hard links (some FUSE and SMB mounts): link(2) fails with one of these.
bool no_hard_links(int err) { return err == EPERM || err == ENOTSUP || err == EOPNOTSUPP || err == ENOSYS || err == EMLINK; }
}  // namespace

std::string errno_text(int err) {
  std::string s = std::generic_category().message(err);
  if (s.size() > 1 && std::isupper(static_cast<unsigned char>(s[0])) && std::islower(static_cast<unsigned char>(s[1])))
    s[0] = static_cast<char>(std::tolower(static_cast<unsigned char>(s[0])));
  return s;
}

std::string writer_tag() {
  char host[256] = "";
  gethostname(host, sizeof host - 1);
  std::string h = host;
  for (char& c : h)
    if (c == '/' || c == '.') c = '_';  // the tag is read back up to its first '.'
  return std::to_string(::getpid()) + "@" + h.substr(0, 64);
}

std::string random_hex8() {
  static std::mutex m;  // random_device is not promised to be thread-safe
  std::lock_guard<std::mutex> g(m);
  static std::random_device rd;
  char b[16];
  std::snprintf(b, sizeof b, "%08x", static_cast<unsigned>(rd()));
  return b;
}

namespace {
// ".NAME." and ".tmp": a temporary file of NAME is .NAME.<8 hex>.<pid>@<host>.tmp.
std::string temporary_head(const std::string& target) {
  std::string head(1, '.');  // built by appends: GCC 12 warns (falsely, -Wrestrict) on "." + name + "."
  head += fs::path(target).filename().string();
  head += '.';
  return head;
}
constexpr const char* temporary_tail = ".tmp";
}  // namespace

TmpFile::TmpFile(std::string path, std::string shown, bool locked)
    : path_(std::move(path)), shown_(shown.empty() ? path_ : std::move(shown)) {
  if (!locked) remove_stale_temporaries(path_);
  const fs::path dir = fs::path(path_).parent_path();
  for (int attempt = 0; fd_ < 0; ++attempt) {
    tmp_ = (dir / (temporary_head(path_) + random_hex8() + "." + writer_tag() + temporary_tail)).string();
    fd_ = ::open(tmp_.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
    if (fd_ >= 0) break;
    const int e = errno;  // before anything else can change it
    if (e != EEXIST || attempt > 8)
      throw WriteError(shown_, e, "cannot write " + shown_ + ": " + errno_text(e) + " (" + shown_ + " is left as it was)");
  }
}

TmpFile::~TmpFile() {
  if (committed_) return;
  if (fd_ >= 0) ::close(fd_);
  ::unlink(tmp_.c_str());
}

void TmpFile::fail(const std::string& verb, int err) {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
  ::unlink(tmp_.c_str());
  throw WriteError(shown_, err, "cannot " + verb + ": " + errno_text(err) + " (" + shown_ + " is left as it was)");
}

void TmpFile::put(const char* data, std::size_t n) {
  if (const int e = io_fault::next_write()) fail("write " + shown_, e);
  while (n > 0) {
    const ssize_t k = ::write(fd_, data, n);
    if (k < 0 && errno == EINTR) continue;
    if (k < 0) {
      const int e = errno;
      fail("write " + shown_, e);
    }
    if (k == 0) fail("write " + shown_, ENOSPC);  // no progress on a regular file: the device is full
    data += k;
    n -= static_cast<std::size_t>(k);
  }
}

void TmpFile::write(const void* data, std::size_t n) {
  const char* p = static_cast<const char*>(data);
  if (!pending_.empty()) {
    const std::size_t k = std::min(n, write_chunk - pending_.size());
    pending_.append(p, k);
    p += k;
    n -= k;
    if (pending_.size() < write_chunk) return;
    put(pending_.data(), pending_.size());
    pending_.clear();
  }
  for (; n >= write_chunk; p += write_chunk, n -= write_chunk) put(p, write_chunk);
  pending_.assign(p, n);
}

void TmpFile::write_text(const std::function<void(std::FILE*)>& body) {
  // A stdio stream whose writes land in this file; an exception must not cross stdio's C
  // frames, so the first one is kept and thrown once the body is done.
  struct Cookie {
    TmpFile* file;
    std::exception_ptr error;
  } cookie{this, nullptr};
  cookie_io_functions_t io{};
  io.write = [](void* c, const char* buf, size_t n) -> ssize_t {
    auto* k = static_cast<Cookie*>(c);
    if (k->error) return 0;
    try {
      k->file->write(buf, n);
      return static_cast<ssize_t>(n);
    } catch (...) {
      k->error = std::current_exception();
      return 0;
    }
  };
  std::FILE* f = ::fopencookie(&cookie, "w", io);
  if (!f) {
    const int e = errno;
    fail("write " + shown_, e);
  }
  try {
    body(f);
  } catch (...) {
    std::fclose(f);
    throw;
  }
  const bool ok = std::fflush(f) == 0 && !std::ferror(f);
  std::fclose(f);
  if (cookie.error) std::rethrow_exception(cookie.error);
  if (!ok) fail("write " + shown_, EIO);
}

void TmpFile::finish() {
  if (fd_ < 0) return;
  if (!pending_.empty()) put(pending_.data(), pending_.size());
  pending_.clear();
  if (const int e = io_fault::next_write()) fail("flush " + shown_ + " to disk", e);
  io_fault::durable_step();
  if (::fsync(fd_) != 0) {
    const int e = errno;
    fail("flush " + shown_ + " to disk", e);
  }
  if (::close(std::exchange(fd_, -1)) != 0) {
    const int e = errno;
    fail("close " + shown_, e);
  }
}

void TmpFile::commit() {
  finish();
  int e = io_fault::next_rename();
  io_fault::durable_step();
  if (e == 0 && ::rename(tmp_.c_str(), path_.c_str()) != 0) e = errno;
  if (e) fail("write " + shown_ + " (rename into place)", e);
  committed_ = true;
  fsync_folder(path_);
}

bool TmpFile::commit_new() {
  finish();
  int e = io_fault::next_rename();
  io_fault::durable_step();
  if (e == 0 && ::link(tmp_.c_str(), path_.c_str()) != 0) e = errno;
  if (e == EEXIST) {  // over NFS a retried link that had succeeded says EEXIST: PATH is then this file
    struct stat a {}, b {};
    if (::stat(tmp_.c_str(), &a) != 0 || ::stat(path_.c_str(), &b) != 0 || a.st_ino != b.st_ino || a.st_dev != b.st_dev) return false;
    e = 0;
  }
  if (no_hard_links(e)) {  // the caller holds the file's lock: a rename cannot meet another writer's file
    e = 0;
    if (::rename(tmp_.c_str(), path_.c_str()) != 0) e = errno;
    else committed_ = true;
  }
  if (e) fail("write " + shown_ + " (link into place)", e);
  if (!committed_) ::unlink(tmp_.c_str());  // the file is PATH now; a kill before this leaves a stale temporary
  committed_ = true;
  fsync_folder(path_);
  return true;
}

void make_parent(const std::string& path) {
  const fs::path parent = fs::path(path).parent_path();
  std::error_code ec;
  if (!parent.empty()) fs::create_directories(parent, ec);
}

bool is_temporary_of(const std::string& name, const std::string& target) {
  const std::string head = temporary_head(target);
  return name.size() > head.size() + 4 && name.compare(0, head.size(), head) == 0 && name.ends_with(temporary_tail) &&
         name.find('.', head.size()) == head.size() + 8;  // the 8 hex digits, then the writer
}

void remove_stale_temporaries(const std::string& path, bool all) {
  const fs::path dir = fs::path(path).parent_path();
  const std::string head = temporary_head(path), mine = writer_tag();
  const std::string host = mine.substr(mine.find('@'));
  std::error_code ec;
  for (fs::directory_iterator it(dir.empty() ? fs::path(".") : dir, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (!is_temporary_of(name, path)) continue;
    // .NAME.<hex8>.<pid>@<host>.tmp: gone when made here by a process that no longer exists.
    const std::string writer = name.substr(head.size() + 9, name.size() - head.size() - 9 - 4);
    const size_t at = writer.find('@');
    bool gone = all;
    if (!gone && at != std::string::npos && writer.substr(at) == host) {
      const long pid = std::strtol(writer.substr(0, at).c_str(), nullptr, 10);
      gone = pid > 0 && ::kill(static_cast<pid_t>(pid), 0) != 0 && errno == ESRCH;
    }
    if (gone) fs::remove(it->path(), ec);  // a race with another cleaner is harmless
    ec.clear();
  }
}

void write_text_atomically(const std::string& path, const std::function<void(std::FILE*)>& body) {
  make_parent(path);
  TmpFile tmp(path);
  tmp.write_text(body);
  tmp.commit();
}

void write_file_atomically(const std::string& path, const void* data, std::size_t n) {
  make_parent(path);
  TmpFile tmp(path);
  tmp.write(data, n);
  tmp.commit();
}

}  // namespace xb
