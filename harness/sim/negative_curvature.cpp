#include "negative_curvature.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>

namespace xb {

namespace {
// One element's mode on K's dofs: up to 4 dof blocks (−1: pinned or absent) and 12 values.
struct Mode {
  std::array<int, 4> block{-1, -1, -1, -1};
  Eigen::Matrix<double, 12, 1> v;
};

// vᵀKv restricted to the mode's own dofs (its other entries are zero) and vᵀDv.
void quadratic_forms(const SparseMatrix& K, const Vector& D, const Mode& m, double& vKv, double& vDv) {
  vKv = vDv = 0;
  const int* outer = K.outerIndexPtr();
  const int* cols = K.innerIndexPtr();
  const double* val = K.valuePtr();
  for (int a = 0; a < 4; ++a) {
    if (m.block[a] < 0) continue;
    for (int d = 0; d < 3; ++d) {
      const int row = 3 * m.block[a] + d;
      const double vr = m.v[3 * a + d];
      if (vr == 0) continue;
      vDv += D[row] * vr * vr;
      for (int k = outer[row]; k < outer[row + 1]; ++k) {
        const int cb = cols[k] / 3;
        for (int b = 0; b < 4; ++b)
          if (m.block[b] == cb) vKv += vr * val[k] * m.v[3 * b + cols[k] % 3];
      }
    }
  }
}

void add_mode(const Mode& m, double scale, Vector& out) {
  for (int a = 0; a < 4; ++a)
    if (m.block[a] >= 0) out.segment<3>(3 * m.block[a]) += scale * m.v.segment<3>(3 * a);
}
}  // namespace

NegativeCurvature negative_curvature(const Problem& prob, const ElementHessians& eh, const Eigen::Matrix3Xd& x,
                                     const Eigen::VectorXd& alpha_tilde, const PrimalSystem& sys, const SparseMatrix& K,
                                     const Vector& D, const Vector& g, const std::vector<int>& held, int max_candidates) {
  NegativeCurvature out;
  const std::vector<double>& low = eh.smallest_eigenvalues();
  std::vector<int> order;
  for (int j = 0; j < static_cast<int>(low.size()); ++j)
    if (low[j] < 0) order.push_back(j);
  const size_t take = std::min(order.size(), static_cast<size_t>(std::max(0, max_candidates)));
  std::partial_sort(order.begin(), order.begin() + static_cast<long>(take), order.end(),
                    [&](int a, int b) { return low[a] < low[b] || (low[a] == low[b] && a < b); });
  order.resize(take);
  std::vector<int> block_of(prob.particles.size(), -1);
  const auto& free = sys.free_particles();
  for (size_t i = 0; i < free.size(); ++i) block_of[free[i]] = static_cast<int>(i);
  std::vector<char> near(free.size(), 0);  // a dof block K couples to a chosen mode's
  const long n = K.rows();
  std::vector<char> is_held(n, 0);
  for (int d : held) is_held[d] = 1;
  out.combined = Vector::Zero(n);
  Mode m;
  for (int j : order) {
    ++out.candidates;
    eh.lowest_mode(x, alpha_tilde, j, m.v);
    const auto ps = prob.constraint_particles(j);
    for (int a = 0; a < 4; ++a) {
      m.block[a] = ps[a] >= 0 ? block_of[ps[a]] : -1;
      for (int d = 0; d < 3 && m.block[a] >= 0; ++d)
        if (is_held[3 * m.block[a] + d]) m.v[3 * a + d] = 0;
    }
    double vKv, vDv;
    quadratic_forms(K, D, m, vKv, vDv);
    if (!(vDv > 0) || !(vKv < 0)) continue;
    ++out.negative;
    double gv = 0;
    for (int a = 0; a < 4; ++a)
      if (m.block[a] >= 0) gv += g.segment<3>(3 * m.block[a]).dot(m.v.segment<3>(3 * a));
    const double scale = (gv > 0 ? -1.0 : 1.0) / std::sqrt(vDv);
    if (vKv / vDv < out.smallest) {
      out.smallest = vKv / vDv;
      out.best = Vector::Zero(n);
      add_mode(m, scale, out.best);
    }
    bool free_of_others = true;
    for (int a = 0; a < 4; ++a)
      if (m.block[a] >= 0 && near[m.block[a]]) free_of_others = false;
    if (!free_of_others) continue;
    add_mode(m, scale, out.combined);
    ++out.combined_modes;
    for (int a = 0; a < 4; ++a) {
      if (m.block[a] < 0) continue;
      const int row = 3 * m.block[a];
      for (int k = K.outerIndexPtr()[row]; k < K.outerIndexPtr()[row + 1]; ++k) near[K.innerIndexPtr()[k] / 3] = 1;
    }
  }
  if (out.combined_modes == 0) {
    out.combined.resize(0);
  } else {
    out.combined /= std::sqrt((out.combined.array().square() * D.array()).sum());
  }
  return out;
}

}  // namespace xb
