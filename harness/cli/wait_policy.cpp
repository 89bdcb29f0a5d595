#include "wait_policy.hpp"

#include <dlfcn.h>
#include <unistd.h>

#include <cstdlib>
#include <string>

namespace xb {

// Loop guard: XB_WAIT_POLICY_REEXEC holds the pid that re-executed; the new image (same pid) sees
// it, never re-executes again, and removes it so that child processes start clean.
void ensure_bounded_wait_policy(char** argv) {
  constexpr const char* marker = "XB_WAIT_POLICY_REEXEC";
  const std::string pid = std::to_string(::getpid());
  const char* m = std::getenv(marker);
  const bool reexecuted = m && pid == m;
  if (m) ::unsetenv(marker);
  if (reexecuted || std::getenv("OMP_WAIT_POLICY")) return;
  const bool set_spin = !std::getenv("GOMP_SPINCOUNT");
  if (::setenv("OMP_WAIT_POLICY", "passive", 1) == 0 && (!set_spin || ::setenv("GOMP_SPINCOUNT", kSpinCount, 1) == 0) &&
      ::setenv(marker, pid.c_str(), 1) == 0)
    ::execv("/proc/self/exe", argv);
  // Only reached if a setenv or execv failed: run on with the runtime's default policy, which the
  // run's provenance (omp_wait_policy = default) and `report` then show.
  ::unsetenv("OMP_WAIT_POLICY");
  if (set_spin) ::unsetenv("GOMP_SPINCOUNT");
  ::unsetenv(marker);
}

void limit_blas_threads() {
  if (std::getenv("OPENBLAS_NUM_THREADS")) return;
  if (auto set = reinterpret_cast<void (*)(int)>(::dlsym(RTLD_DEFAULT, "openblas_set_num_threads"))) set(1);
}

}  // namespace xb
