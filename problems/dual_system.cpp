#include "dual_system.hpp"

#include <algorithm>
#include <numeric>

namespace xb {

DualSystem::DualSystem(const Problem& prob) : prob_(prob) {
  build_incidence();
  build_pattern();
}

void DualSystem::build_incidence() {
  const Problem& prob = prob_;
  const int m = prob.num_constraints();
  const int n = prob.particles.size();
  // Particle → (constraint, slot) incidence.
  inc_start_.assign(n + 1, 0);
  for (int j = 0; j < m; ++j)
    for (int p : prob.constraint_particles(j))
      if (p >= 0) ++inc_start_[p + 1];
  std::partial_sum(inc_start_.begin(), inc_start_.end(), inc_start_.begin());
  inc_.resize(inc_start_[n]);
  {
    std::vector<int> fillpos(inc_start_.begin(), inc_start_.end() - 1);
    for (int j = 0; j < m; ++j) {
      const auto ps = prob.constraint_particles(j);
      for (int s = 0; s < 4; ++s)
        if (ps[s] >= 0) inc_[fillpos[ps[s]]++] = {j, s};
    }
  }
}

void DualSystem::build_pattern() {
  const Problem& prob = prob_;
  const int m = prob.num_constraints();
  const Eigen::VectorXd& w = prob.particles.w;

  // Per row: the coupled constraints and the (slot, slot) pairs of shared free particles.
  // Rows are independent; build them in parallel into per-row buffers, then concatenate.
  struct Entry {
    int col;
    std::uint8_t pair;
  };
  std::vector<std::vector<Entry>> row_entries(m);
#pragma omp parallel for schedule(dynamic, 256)
  for (int i = 0; i < m; ++i) {
    auto& es = row_entries[i];
    const auto ps = prob.constraint_particles(i);
    for (int a = 0; a < 4; ++a) {
      const int p = ps[a];
      if (p < 0 || w[p] == 0) continue;  // pinned particles couple nothing
      for (int k = inc_start_[p]; k < inc_start_[p + 1]; ++k)
        es.push_back({inc_[k].constraint, static_cast<std::uint8_t>(a << 2 | inc_[k].slot)});
    }
    // The diagonal exists even for a constraint with only pinned particles (A_ii = α̃).
    bool has_diag = false;
    for (const auto& e : es) has_diag |= e.col == i;
    if (!has_diag) es.push_back({i, 0xFF});
    std::stable_sort(es.begin(), es.end(), [](const Entry& x, const Entry& y) { return x.col < y.col; });
  }

  std::vector<int> outer(m + 1, 0);
  for (int i = 0; i < m; ++i) {
    int cols = 0;
    for (size_t k = 0; k < row_entries[i].size(); ++k)
      if (k == 0 || row_entries[i][k].col != row_entries[i][k - 1].col) ++cols;
    outer[i + 1] = outer[i] + cols;
  }
  const int nnz = outer[m];
  A_.resize(m, m);
  A_.resizeNonZeros(nnz);
  std::copy(outer.begin(), outer.end(), A_.outerIndexPtr());
  pair_start_.assign(nnz + 1, 0);
  diag_.assign(m, -1);
  std::vector<int> pair_count(nnz, 0);
  int* cols = A_.innerIndexPtr();
#pragma omp parallel for schedule(dynamic, 256)
  for (int i = 0; i < m; ++i) {
    int k = outer[i] - 1;
    int prev = -1;
    for (const auto& e : row_entries[i]) {
      if (e.col != prev) {
        cols[++k] = e.col;
        prev = e.col;
        if (e.col == i) diag_[i] = k;
      }
      if (e.pair != 0xFF) ++pair_count[k];
    }
  }
  for (int k = 0; k < nnz; ++k) pair_start_[k + 1] = pair_start_[k] + pair_count[k];
  pairs_.resize(pair_start_[nnz]);
#pragma omp parallel for schedule(dynamic, 256)
  for (int i = 0; i < m; ++i) {
    int k = outer[i] - 1;
    int prev = -1;
    int pos = 0;
    for (const auto& e : row_entries[i]) {
      if (e.col != prev) {
        ++k;
        prev = e.col;
        pos = pair_start_[k];
      }
      if (e.pair != 0xFF) pairs_[pos++] = e.pair;
    }
  }
  std::fill(A_.valuePtr(), A_.valuePtr() + nnz, 0.0);
}

void DualSystem::fill(const ConstraintState& s, const Eigen::VectorXd& alpha_tilde) {
  const int m = rows();
  const int* outer = A_.outerIndexPtr();
  const int* cols = A_.innerIndexPtr();
  double* val = A_.valuePtr();
  const Eigen::VectorXd& w = prob_.particles.w;
#pragma omp parallel for schedule(static)
  for (int i = 0; i < m; ++i) {
    const auto ps = prob_.constraint_particles(i);
    const auto& gi = s.grad[i];
    for (int k = outer[i]; k < outer[i + 1]; ++k) {
      const auto& gj = s.grad[cols[k]];
      double v = 0;
      for (int q = pair_start_[k]; q < pair_start_[k + 1]; ++q) {
        const int a = pairs_[q] >> 2, b = pairs_[q] & 3;
        v += w[ps[a]] * gi[a].dot(gj[b]);
      }
      val[k] = v;
    }
    val[diag_[i]] += alpha_tilde[i];
  }
}

void DualSystem::apply_gradT(const ConstraintState& s, const Eigen::VectorXd& y, Eigen::Matrix3Xd& out) const {
  const int n = prob_.particles.size();
  out.resize(3, n);
#pragma omp parallel for schedule(static)
  for (int p = 0; p < n; ++p) {
    Eigen::Vector3d acc = Eigen::Vector3d::Zero();
    for (int k = inc_start_[p]; k < inc_start_[p + 1]; ++k)
      acc += s.grad[inc_[k].constraint][inc_[k].slot] * y[inc_[k].constraint];
    out.col(p) = acc;
  }
}

void DualSystem::apply_minv_gradT(const ConstraintState& s, const Eigen::VectorXd& y, Eigen::Matrix3Xd& out) const {
  apply_gradT(s, y, out);
  const Eigen::VectorXd& w = prob_.particles.w;
#pragma omp parallel for schedule(static)
  for (int p = 0; p < static_cast<int>(out.cols()); ++p) out.col(p) *= w[p];
}

}  // namespace xb
