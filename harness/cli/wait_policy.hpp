// How the harness's binaries make their OpenMP timings honest however they are started.
#pragma once

namespace xb {

// The spin before a waiting OpenMP thread sleeps (GOMP_SPINCOUNT), set with OMP_WAIT_POLICY =
// passive when the user has chosen no policy. About 0.3 ms on the 2-core test machine: long enough
// that back-to-back parallel regions (a V-cycle has ~40) do not each pay a futex wake-up (120 µs
// per region there with no spin: a third of a primal V-cycle), short enough that a thread waiting
// for a descheduled sibling sleeps instead of spinning away a loaded machine's cores (libgomp's
// default spins ~10 ms; `active` forever, which made solves 10–100× slower under load).
inline constexpr const char* kSpinCount = "10000";

// When OMP_WAIT_POLICY is unset: set it to passive and, unless the user set GOMP_SPINCOUNT, that
// to kSpinCount, then re-execute this binary (same pid, argv and environment, so an mpirun launch
// stays intact). libgomp reads both in its load-time constructor, before main, so this must run
// first in main, before MPI_Init or any OpenMP call. A policy the user set is theirs: left alone.
void ensure_bounded_wait_policy(char** argv);

// OpenBLAS (CHOLMOD's supernodal BLAS) runs its own pool of threads beside the OpenMP team. On the
// 2-core machine under load its synchronisation made CHOLMOD's analysis + factorisation of the
// captured cloth 256² system 13× slower (load 10: 13.2 s with 2 threads against 0.97 s with one),
// while on a quiet machine one thread is as fast (0.634 s against 0.642 s): one thread unless
// OPENBLAS_NUM_THREADS is set. A BLAS other than OpenBLAS is left alone. Runs record the count
// (`blas_threads`).
void limit_blas_threads();

}  // namespace xb
