// xb::Error: bad input (spec, mesh, flag, parameter). The CLI prints what() as one line and
// exits non-zero; the message names the file, line or key and what is wrong.
#pragma once
#include <new>
#include <stdexcept>
#include <string>

namespace xb {
struct Error : std::runtime_error {
  using std::runtime_error::runtime_error;
};
// Out of memory, with why (the memory limit, the size a factor would need): a std::bad_alloc, so
// that every handler of a failed allocation takes it, and the run ends with status out_of_memory.
struct OutOfMemory : std::bad_alloc {
  explicit OutOfMemory(std::string what) : what_(std::move(what)) {}
  const char* what() const noexcept override { return what_.c_str(); }

 private:
  std::string what_;
};
}  // namespace xb
