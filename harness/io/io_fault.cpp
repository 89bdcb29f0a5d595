#include "io_fault.hpp"

#include "../../core/error.hpp"

#include <csignal>
#include <cerrno>
#include <cstdlib>
#include <mutex>

namespace xb::io_fault {

namespace {

struct Fault {
  long at = 0;  // the call that fails (1-based); 0: none
  int err = 0;  // the errno, or for the signal hook the signal
  long calls = 0;
};

struct Faults {
  Fault write, rename, lock, signal;
};

long write_total = 0, step_total = 0;  // every write call and durable step, fault or not

struct Name {
  const char* name;
  int value;
};
const Name errnos[] = {{"ENOSPC", ENOSPC}, {"EFBIG", EFBIG}, {"EROFS", EROFS}, {"EDQUOT", EDQUOT},
                       {"EIO", EIO},       {"EACCES", EACCES}, {"ENOLCK", ENOLCK}};
const Name signals[] = {{"SIGKILL", SIGKILL}, {"SIGSTOP", SIGSTOP}};

template <size_t K>
Fault parse(const char* var, const std::string& value, const Name (&names)[K], const char* expected) {
  if (value.empty()) return {};
  const auto colon = value.find(':');
  const std::string n = value.substr(0, colon), e = colon == std::string::npos ? "" : value.substr(colon + 1);
  char* end = nullptr;
  const long at = std::strtol(n.c_str(), &end, 10);
  for (const auto& c : names)
    if (e == c.name && !n.empty() && *end == '\0' && at >= 1) return {at, c.value, 0};
  throw Error(std::string(var) + "=" + value + ": expected " + expected);
}

Fault parse_errno(const char* var, const std::string& value) {
  return parse(var, value, errnos,
               "N:ERRNO (N >= 1, the call that fails; ERRNO one of ENOSPC, EFBIG, EROFS, EDQUOT, EIO, EACCES, ENOLCK)");
}

std::mutex lock;  // the counts stay exact when threads write at once

std::string env(const char* name) {
  const char* v = std::getenv(name);
  return v ? v : "";
}

Faults& faults() {
  static Faults f{parse_errno("XB_FAULT_WRITE", env("XB_FAULT_WRITE")), parse_errno("XB_FAULT_RENAME", env("XB_FAULT_RENAME")),
                  parse_errno("XB_FAULT_LOCK", env("XB_FAULT_LOCK")),
                  parse("XB_FAULT_SIGNAL", env("XB_FAULT_SIGNAL"), signals, "N:SIGNAL (N >= 1, the step; SIGNAL SIGKILL or SIGSTOP)")};
  return f;
}

int next(Fault Faults::*which) {
  std::lock_guard<std::mutex> g(lock);
  if (which == &Faults::write) ++write_total;
  if (which == &Faults::signal) ++step_total;
  Fault& f = faults().*which;
  if (f.at == 0) return 0;
  return ++f.calls == f.at ? f.err : 0;
}

}  // namespace

int next_write() { return next(&Faults::write); }
int next_rename() { return next(&Faults::rename); }
int next_lock() { return next(&Faults::lock); }

void durable_step() {
  if (const int sig = next(&Faults::signal)) std::raise(sig);
}

long write_calls() {
  std::lock_guard<std::mutex> g(lock);
  return write_total;
}

long steps() {
  std::lock_guard<std::mutex> g(lock);
  return step_total;
}

void set(const std::string& write, const std::string& rename, const std::string& lock_fault) {
  Fault w = parse_errno("XB_FAULT_WRITE", write), r = parse_errno("XB_FAULT_RENAME", rename);
  Fault l = parse_errno("XB_FAULT_LOCK", lock_fault);
  std::lock_guard<std::mutex> g(lock);
  faults() = Faults{w, r, l, faults().signal};
}

}  // namespace xb::io_fault
