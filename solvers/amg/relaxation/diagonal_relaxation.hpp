// The polynomial smoothers in D⁻¹A — jacobi (x += D⁻¹(b − Ax)/λ) and degree-3 chebyshev — with D
// the scalar diagonal or the node-block diagonal, in double or single (float) storage. Each step
// is one fused pass over A: d = c₁d + c₂D⁻¹(b − Ax), the residual never stored, then x += d.
// The double smoothers (smoothers.cpp, block_chebyshev.cpp) and the V-cycle's float copy
// (single_levels.hpp) run the same code.
#pragma once

#include "../../../core/sparse.hpp"

#include <array>
#include <vector>

namespace xb::amg {

struct BlockOperator;

template <class S>
struct DiagonalRelaxation {
  bool chebyshev = true;  // false: jacobi
  int sweeps = 1;
  int degree = 3;         // chebyshev: the polynomial's degree (passes over A per sweep)
  double lambda = 0;      // the λ_max(D⁻¹A) estimate
  // D⁻¹: the scalar inverse diagonal, or (node_start not empty) row-major node blocks, node I's
  // at block_inv[offset[I]].
  VectorOf<S> inv_diag;
  std::vector<int> node_start;
  std::vector<long> offset;
  std::vector<S> block_inv;
  // A's node blocks (block_kernels.hpp), when A is node-block CSR in node_start's layout: the
  // step then reads A by blocks. Not owned.
  const BlockOperator* blocks = nullptr;

  // One sweep's steps (c1, c2): d = c1·d + c2·D⁻¹(b − Ax), then x += d, in order (jacobi: one
  // step (0, 1/λ); chebyshev: `degree` steps of its three-term recurrence). presmooth runs these;
  // the hierarchy's export (hierarchy_export.hpp) hands them to other implementations.
  std::vector<std::array<double, 2>> steps() const;
  // x_zero: x is zero on entry (one product with A saved).
  void presmooth(const CsrOf<S>& A, const VectorOf<S>& b, VectorOf<S>& x, bool x_zero);
  void postsmooth(const CsrOf<S>& A, const VectorOf<S>& b, VectorOf<S>& x) { presmooth(A, b, x, false); }
  // d = c1·d + c2·D⁻¹(b − A x) in one pass over A (c1 = 0: d is overwritten, not read).
  void step(const CsrOf<S>& A, const VectorOf<S>& b, const VectorOf<S>& x, double c1, double c2);
  // d = c·D⁻¹b.
  void scale(const VectorOf<S>& b, double c);

  VectorOf<S> d;  // work
};

// The same smoother with single-precision storage.
DiagonalRelaxation<float> to_single(const DiagonalRelaxation<double>& r);

extern template struct DiagonalRelaxation<double>;
extern template struct DiagonalRelaxation<float>;

}  // namespace xb::amg
