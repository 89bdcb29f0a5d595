// Sums over a parallel loop that give the same bits for any thread count (the design card:
// "reductions over fixed chunks in a fixed order"). The index range [0, n) is cut into chunks of
// `reduce_chunk` indices — fixed by n, never by the number of threads — each chunk is summed in
// index order by one thread, and the chunk sums are added in chunk order on the calling thread.
// An OpenMP `reduction(+ : s)` instead adds one partial sum per thread, so its rounding (and every
// iteration count and residual downstream) changes with OMP_NUM_THREADS.
#pragma once

#include <omp.h>

#include <algorithm>
#include <array>
#include <vector>

namespace xb {

// Indices per chunk: large enough that the chunk sums cost nothing against the loop (a 270K-row
// vector has 264 chunks), small enough that 2–16 threads get balanced work from a few thousand
// rows up (spmv_dot's row blocks move to chunk boundaries: at most 512 rows off balance).
constexpr long reduce_chunk = 1024;

inline long reduce_chunks(long n) { return n <= 0 ? 0 : (n + reduce_chunk - 1) / reduce_chunk; }

// K sums at once over [0, n): chunk_sum(lo, hi, acc) adds the terms of indices lo..hi-1, in index
// order, into acc (K doubles, zero on entry). Returns the K totals. One parallel region, whose
// thread t of T takes the chunks from the chunk boundary nearest block_start(t, T) to the one
// nearest block_start(t + 1, T): blocks balanced by any measure (SpMV's rows of about equal
// non-zeros, kernels.cpp), cut on chunk boundaries so that each chunk is summed whole by one
// thread. block_start must be non-decreasing in t, with values in [0, n]. Deterministic for any
// thread count; no allocation after a thread's first call with as many chunks.
template <int K, class BlockStart, class ChunkSum>
std::array<double, K> deterministic_sums_in_blocks(long n, BlockStart&& block_start, ChunkSum&& chunk_sum) {
  std::array<double, K> total{};
  const long nc = reduce_chunks(n);
  if (nc <= 1) {
    if (n > 0) chunk_sum(0L, n, total.data());
    return total;
  }
  thread_local std::vector<double> partial;
  partial.assign(static_cast<std::size_t>(nc) * K, 0.0);
  double* part = partial.data();
#pragma omp parallel
  {
    const int t = omp_get_thread_num(), T = omp_get_num_threads();
    auto first_chunk = [&](int k) -> long {
      if (k <= 0) return 0;
      if (k >= T) return nc;
      return std::min(nc, (static_cast<long>(block_start(k, T)) + reduce_chunk / 2) / reduce_chunk);
    };
    const long c1 = first_chunk(t + 1);
    for (long c = first_chunk(t); c < c1; ++c)
      chunk_sum(c * reduce_chunk, std::min(n, (c + 1) * reduce_chunk), part + c * K);
  }
  for (long c = 0; c < nc; ++c)
    for (int k = 0; k < K; ++k) total[k] += part[c * K + k];
  return total;
}

// The same with blocks of equal index counts.
template <int K, class ChunkSum>
std::array<double, K> deterministic_sums(long n, ChunkSum&& chunk_sum) {
  return deterministic_sums_in_blocks<K>(n, [n](int t, int T) { return n * t / T; }, chunk_sum);
}

// One sum: Σ_i term(i) over [0, n), the terms of a chunk added in index order.
template <class Term>
double deterministic_sum(long n, Term&& term) {
  return deterministic_sums<1>(n, [&](long lo, long hi, double* acc) {
    double s = 0;
    for (long i = lo; i < hi; ++i) s += term(i);
    acc[0] = s;
  })[0];
}

}  // namespace xb
