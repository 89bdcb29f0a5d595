// xb::Error: bad input (spec, mesh, flag, parameter). The CLI prints what() as one line and
// exits non-zero; the message names the file, line or key and what is wrong.
#pragma once
#include <stdexcept>
#include <string>

namespace xb {
struct Error : std::runtime_error {
  using std::runtime_error::runtime_error;
};
}  // namespace xb
