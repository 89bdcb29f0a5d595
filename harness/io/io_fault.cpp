#include "io_fault.hpp"

#include "../../core/error.hpp"

#include <cerrno>
#include <cstdlib>
#include <mutex>

namespace xb::io_fault {

namespace {

struct Fault {
  long at = 0;  // the call that fails (1-based); 0: none
  int err = 0;
  long calls = 0;
};

struct Faults {
  Fault write, rename;
};

long write_total = 0;  // every write call, fault or not

Fault parse(const char* var, const std::string& value) {
  if (value.empty()) return {};
  static const struct {
    const char* name;
    int err;
  } names[] = {{"ENOSPC", ENOSPC}, {"EFBIG", EFBIG}, {"EROFS", EROFS}, {"EDQUOT", EDQUOT}, {"EIO", EIO}, {"EACCES", EACCES}};
  const auto colon = value.find(':');
  const std::string n = value.substr(0, colon), e = colon == std::string::npos ? "" : value.substr(colon + 1);
  char* end = nullptr;
  const long at = std::strtol(n.c_str(), &end, 10);
  for (const auto& c : names)
    if (e == c.name && !n.empty() && *end == '\0' && at >= 1) return {at, c.err, 0};
  throw Error(std::string(var) + "=" + value +
              ": expected N:ERRNO (N >= 1, the call that fails; ERRNO one of ENOSPC, EFBIG, EROFS, EDQUOT, EIO, EACCES)");
}

std::mutex lock;  // writes come from one thread; the lock only keeps the counts exact if not

Faults& faults() {
  static Faults f = [] {
    const char* w = std::getenv("XB_FAULT_WRITE");
    const char* r = std::getenv("XB_FAULT_RENAME");
    return Faults{parse("XB_FAULT_WRITE", w ? w : ""), parse("XB_FAULT_RENAME", r ? r : "")};
  }();
  return f;
}

int next(Fault Faults::*which) {
  std::lock_guard<std::mutex> g(lock);
  if (which == &Faults::write) ++write_total;
  Fault& f = faults().*which;
  if (f.at == 0) return 0;
  return ++f.calls == f.at ? f.err : 0;
}

}  // namespace

int next_write() { return next(&Faults::write); }
int next_rename() { return next(&Faults::rename); }

long write_calls() {
  std::lock_guard<std::mutex> g(lock);
  return write_total;
}

void set(const std::string& write, const std::string& rename) {
  Fault w = parse("XB_FAULT_WRITE", write), r = parse("XB_FAULT_RENAME", rename);
  std::lock_guard<std::mutex> g(lock);
  faults() = Faults{w, r};
}

}  // namespace xb::io_fault
