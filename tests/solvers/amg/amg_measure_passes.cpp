// The bytes each pass of one V-cycle (and of CG's product with K) reads and writes, against the
// triad's bandwidth measured in the same process: the per-pass finding of docs/kernels.md.
// Bytes are the compulsory traffic of each kernel as it runs: values, the index arrays
// it reads (one column node per block, the row pointers per node), the vectors read once, and
// each vector written counted twice (its write-allocate read, as the triad counts it). Gathers
// of x beyond one read are not counted, so the floor is a lower bound.
#include "solvers/amg/hierarchy.hpp"
#include "solvers/kernels.hpp"

#include <cstdio>
#include <functional>

namespace xb::test {

using Least = std::function<double(int, const std::function<void()>&)>;

namespace {
struct Pass {
  const char* name;
  double count;   // per V-cycle (or per CG iteration)
  double bytes;   // per pass
  double seconds; // per pass, least of the runs
};

// Bytes one node-block pass over M reads: values, one column index per block, ptr and the CSR
// row pointer (two ints) per row node.
template <class S>
double matrix_bytes(const amg::BlockOperator& op, const CsrOf<S>& M) {
  return sizeof(S) * static_cast<double>(M.nonZeros()) + 4.0 * static_cast<double>(op.pattern.col.size()) +
         12.0 * op.pattern.row_nodes();
}

template <class S>
std::vector<Pass> level_passes(const amg::Level& L, const CsrOf<S>& A, const CsrOf<S>& P, const CsrOf<S>& R,
                               const amg::DiagonalRelaxation<S>& relax, const Least& least) {
  const double n = static_cast<double>(A.rows()), nc = static_cast<double>(P.cols()), s = sizeof(S);
  VectorOf<S> b = VectorOf<S>::Random(A.rows()), x = VectorOf<S>::Random(A.rows()), r(A.rows()), xc = VectorOf<S>::Random(P.cols()),
              bc(P.cols());
  amg::DiagonalRelaxation<S> M = relax;
  M.d = VectorOf<S>::Random(A.rows());
  const int reps = 5;
  const double steps = relax.sweeps * 2.0 * relax.degree - 1;  // the first step from x = 0 is a scaling
  std::vector<Pass> out;
  out.push_back({"smoother step", steps,
                 matrix_bytes(*L.A_blocks, A) + s * (3 * n + 2 * n) + s * static_cast<double>(relax.block_inv.size()),
                 least(reps, [&] { M.step(A, b, x, 0.5, 0.25); })});
  out.push_back({"x += d", relax.sweeps * 2.0 * relax.degree, s * 4 * n, least(reps, [&] {
#pragma omp parallel for schedule(static)
                   for (long i = 0; i < x.size(); ++i) x[i] += M.d[i];
                 })});
  out.push_back({"residual", 1, matrix_bytes(*L.A_blocks, A) + s * (2 * n + 2 * n),
                 least(reps, [&] { amg::block_residual(*L.A_blocks, A, x.data(), b.data(), r.data()); })});
  out.push_back({"residual (CSR)", 0, (s + 4) * static_cast<double>(A.nonZeros()) + 4 * n + s * (2 * n + 2 * n),
                 least(reps, [&] {
                   const int *ao = A.outerIndexPtr(), *ac = A.innerIndexPtr();
                   const S* av = A.valuePtr();
#pragma omp parallel for schedule(static)
                   for (int i = 0; i < static_cast<int>(A.rows()); ++i) r[i] = b[i] - row_dot(ao, ac, av, x.data(), i);
                 })});
  out.push_back({"restriction", 1, matrix_bytes(L.R_blocks, R) + s * (n + 2 * nc),
                 least(reps, [&] { amg::block_multiply(L.R_blocks, R, r.data(), bc.data(), false); })});
  out.push_back({"prolongation (add)", 1, matrix_bytes(L.P_blocks, P) + s * (nc + 3 * n),
                 least(reps, [&] { amg::block_multiply(L.P_blocks, P, xc.data(), x.data(), true); })});
  return out;
}

void print(const char* what, const std::vector<Pass>& passes, double bandwidth, double& bytes, double& floor,
           double& seconds) {
  for (const Pass& p : passes) {
    const double f = p.bytes / bandwidth;
    std::printf("  %-8s %-20s x%-3.0f %8.2f MB  floor %7.3f ms  took %7.3f ms  (%.2fx floor)\n", what, p.name, p.count,
                p.bytes / 1e6, 1e3 * f, 1e3 * p.seconds, p.seconds / f);
    bytes += p.count * p.bytes;
    floor += p.count * f;
    seconds += p.count * p.seconds;
  }
}
}  // namespace

// Per level of h (block levels only), the V-cycle's passes in the storage it runs in (and, not
// counted in the sums, the residual by plain CSR rows for comparison); then CG's product with K.
void measure_passes(const amg::Hierarchy& h, const SparseMatrix& K, double bandwidth, const Least& least) {
  const bool single = h.options().precision == "single";
  double bytes = 0, floor = 0, seconds = 0;
  for (int l = 0; l + 1 < h.num_levels(); ++l) {
    const amg::Level& L = h.level(l);
    if (!L.A_blocks || L.P_blocks.empty() || L.R_blocks.empty() || !L.smoother->relaxation()) {
      std::printf("  level %d: not a block level with a polynomial smoother: passes not measured\n", l);
      continue;
    }
    char what[16];
    std::snprintf(what, sizeof what, "level %d", l);
    if (single)
      print(what, level_passes(L, L.single.A, L.single.P, L.single.R, L.single.relax, least), bandwidth, bytes, floor,
            seconds);
    else
      print(what, level_passes(L, *L.A, L.T.P, L.T.R, *L.smoother->relaxation(), least), bandwidth, bytes, floor,
            seconds);
  }
  std::printf("  V-cycle passes (%s): %.1f MB, floor %.2f ms, sum of passes %.2f ms (%.2fx floor)\n",
              single ? "float" : "double", bytes / 1e6, 1e3 * floor, 1e3 * seconds, seconds / floor);
  const double n = static_cast<double>(K.rows());
  Vector p = Vector::Random(K.rows()), Ap(K.rows());
  std::vector<Pass> cg{{"K p, p'Kp (CSR)", 1, 12.0 * static_cast<double>(K.nonZeros()) + 4 * n + 8 * (n + 2 * n),
                        least(5, [&] { spmv_dot(K, p, Ap); })}};
  double b2 = 0, f2 = 0, s2 = 0;
  print("CG", cg, bandwidth, b2, f2, s2);
  std::fflush(stdout);
}

}  // namespace xb::test
