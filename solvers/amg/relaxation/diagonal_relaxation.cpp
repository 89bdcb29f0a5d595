#include "diagonal_relaxation.hpp"

#include "../../kernels.hpp"
#include "../block_kernels.hpp"

#include <omp.h>

namespace xb::amg {

template <class S>
void DiagonalRelaxation<S>::step(const CsrOf<S>& A, const VectorOf<S>& b, const VectorOf<S>& x, double c1,
                                 double c2) {
  const int n = static_cast<int>(A.rows());
  const int *ao = A.outerIndexPtr(), *ac = A.innerIndexPtr();
  const S* av = A.valuePtr();
  const S *bp = b.data(), *xp = x.data();
  d.resize(n);
  S* dp = d.data();
  if (node_start.empty()) {
    const S* w = inv_diag.data();
#pragma omp parallel if (n > kMinParallelRows)
    {
      int lo, hi;
      row_block(ao, n, omp_get_thread_num(), omp_get_num_threads(), lo, hi);
      for (int i = lo; i < hi; ++i) {
        const double s = c2 * (w[i] * (bp[i] - row_dot(ao, ac, av, xp, i)));
        dp[i] = static_cast<S>(c1 == 0 ? s : c1 * dp[i] + s);
      }
    }
    return;
  }
  if (blocks) {
    block_relax_step(*blocks, A, block_inv.data(), offset.data(), bp, xp, c1, c2, dp);
    return;
  }
  // Node by node: the node's residual rows, then its block of D⁻¹.
  const int nn = static_cast<int>(node_start.size()) - 1;
#pragma omp parallel if (n > kMinParallelRows)
  {
    std::vector<double> res;
#pragma omp for schedule(static)
    for (int I = 0; I < nn; ++I) {
      const int s0 = node_start[I], nb = node_start[I + 1] - s0;
      res.resize(nb);
      for (int r = 0; r < nb; ++r) res[r] = bp[s0 + r] - row_dot(ao, ac, av, xp, s0 + r);
      const S* M = block_inv.data() + offset[I];
      for (int r = 0; r < nb; ++r) {
        double acc = 0;
        for (int c = 0; c < nb; ++c) acc += static_cast<double>(M[r * nb + c]) * res[c];
        dp[s0 + r] = static_cast<S>(c1 == 0 ? c2 * acc : c1 * dp[s0 + r] + c2 * acc);
      }
    }
  }
}

template <class S>
void DiagonalRelaxation<S>::scale(const VectorOf<S>& b, double c) {
  const long n = b.size();
  d.resize(n);
  if (node_start.empty()) {
#pragma omp parallel for schedule(static) if (n > kMinParallelRows)
    for (long i = 0; i < n; ++i) d[i] = static_cast<S>(c * inv_diag[i] * b[i]);
    return;
  }
  const int nn = static_cast<int>(node_start.size()) - 1;
#pragma omp parallel for schedule(static) if (n > kMinParallelRows)
  for (int I = 0; I < nn; ++I) {
    const int s0 = node_start[I], nb = node_start[I + 1] - s0;
    const S* M = block_inv.data() + offset[I];
    for (int r = 0; r < nb; ++r) {
      double acc = 0;
      for (int k = 0; k < nb; ++k) acc += static_cast<double>(M[r * nb + k]) * b[s0 + k];
      d[s0 + r] = static_cast<S>(c * acc);
    }
  }
}

template <class S>
std::vector<std::array<double, 2>> DiagonalRelaxation<S>::steps() const {
  // jacobi: x += D⁻¹(b − Ax)/λ
  if (!chebyshev) return {{0.0, 1.0 / lambda}};
  // Chebyshev of `degree` (3: the authors') for D⁻¹A on [λ/30, 1.1λ] (Saad, Alg. 12.1): a fixed
  // polynomial of D⁻¹A, the same before and after, hence a symmetric V-cycle.
  const double hi = 1.1 * lambda, lo = lambda / 30.0;
  const double theta = 0.5 * (hi + lo), delta = 0.5 * (hi - lo), sigma = theta / delta;
  double rho = 1.0 / sigma;
  std::vector<std::array<double, 2>> c{{0.0, 1.0 / theta}};
  for (int k = 1; k < degree; ++k) {
    const double rho_new = 1.0 / (2.0 * sigma - rho);
    c.push_back({rho_new * rho, 2.0 * rho_new / delta});
    rho = rho_new;
  }
  return c;
}

template <class S>
void DiagonalRelaxation<S>::presmooth(const CsrOf<S>& A, const VectorOf<S>& b, VectorOf<S>& x, bool x_zero) {
  const long n = b.size();
  auto add_d = [&](bool assign) {
    if (assign) x.resize(n);
#pragma omp parallel for schedule(static) if (n > kMinParallelRows)
    for (long i = 0; i < n; ++i) x[i] = assign ? d[i] : x[i] + d[i];
  };
  const std::vector<std::array<double, 2>> c = steps();
  for (int sweep = 0; sweep < sweeps; ++sweep)
    for (size_t k = 0; k < c.size(); ++k) {
      const bool zero = x_zero && sweep == 0 && k == 0;  // d = c2·D⁻¹b: no product with A
      if (zero) scale(b, c[k][1]);
      else step(A, b, x, c[k][0], c[k][1]);
      add_d(zero);
    }
}

DiagonalRelaxation<float> to_single(const DiagonalRelaxation<double>& r) {
  DiagonalRelaxation<float> f;
  f.chebyshev = r.chebyshev;
  f.sweeps = r.sweeps;
  f.degree = r.degree;
  f.lambda = r.lambda;
  f.inv_diag = r.inv_diag.cast<float>();
  f.node_start = r.node_start;
  f.offset = r.offset;
  f.block_inv.assign(r.block_inv.begin(), r.block_inv.end());
  f.blocks = r.blocks;
  return f;
}

template struct DiagonalRelaxation<double>;
template struct DiagonalRelaxation<float>;

}  // namespace xb::amg
