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
  slot_inc_.assign(4L * m, -1);
  particles_.resize(m);
  for (int j = 0; j < m; ++j) particles_[j] = prob.constraint_particles(j);
  {
    std::vector<int> fillpos(inc_start_.begin(), inc_start_.end() - 1);
    for (int j = 0; j < m; ++j) {
      const auto ps = prob.constraint_particles(j);
      for (int s = 0; s < 4; ++s)
        if (ps[s] >= 0) {
          slot_inc_[4 * j + s] = fillpos[ps[s]];
          inc_[fillpos[ps[s]]++] = {j, s};
        }
    }
  }
}

void DualSystem::build_pattern() {
  const Problem& prob = prob_;
  const int m = prob.num_constraints();
  const Eigen::VectorXd& w = prob.particles.w;

  // Per row: its free slots, its number of terms and its columns (the constraints at its free
  // particles, and itself: the diagonal exists even with only pinned particles, A_ii = α̃).
  std::vector<std::vector<int>> row_cols(m);
  free_slots_.assign(m, 0);
  term_start_.assign(m + 1, 0);
#pragma omp parallel for schedule(dynamic, 256)
  for (int i = 0; i < m; ++i) {
    auto& c = row_cols[i];
    c.push_back(i);
    const auto ps = prob.constraint_particles(i);
    for (int a = 0; a < 4; ++a) {
      const int p = ps[a];
      if (p < 0 || w[p] == 0) continue;  // pinned particles couple nothing
      free_slots_[i] |= static_cast<std::uint8_t>(1 << a);
      term_start_[i + 1] += inc_start_[p + 1] - inc_start_[p];
      for (int k = inc_start_[p]; k < inc_start_[p + 1]; ++k) c.push_back(inc_[k].constraint);
    }
    std::sort(c.begin(), c.end());
    c.erase(std::unique(c.begin(), c.end()), c.end());
  }

  std::vector<int> outer(m + 1, 0);
  for (int i = 0; i < m; ++i) outer[i + 1] = outer[i] + static_cast<int>(row_cols[i].size());
  std::partial_sum(term_start_.begin(), term_start_.end(), term_start_.begin());
  const int nnz = outer[m];
  A_.resize(m, m);
  A_.resizeNonZeros(nnz);
  std::copy(outer.begin(), outer.end(), A_.outerIndexPtr());
  diag_.assign(m, -1);
  term_pos_.resize(term_start_[m]);
  int* cols = A_.innerIndexPtr();
#pragma omp parallel for schedule(dynamic, 256)
  for (int i = 0; i < m; ++i) {
    const auto& c = row_cols[i];
    std::copy(c.begin(), c.end(), cols + outer[i]);
    const auto at = [&](int j) { return outer[i] + static_cast<int>(std::lower_bound(c.begin(), c.end(), j) - c.begin()); };
    diag_[i] = at(i);
    const auto ps = prob.constraint_particles(i);
    int t = term_start_[i];
    for (int a = 0; a < 4; ++a)
      if (free_slots_[i] >> a & 1)
        for (int k = inc_start_[ps[a]]; k < inc_start_[ps[a] + 1]; ++k) term_pos_[t++] = at(inc_[k].constraint) - outer[i];
  }
  std::fill(A_.valuePtr(), A_.valuePtr() + nnz, 0.0);
  grad_at_.resize(inc_.size());
}

// Prefetches the gradient runs of row i's free particles (a row's runs are short, so the
// hardware prefetcher does not catch them before they are read).
void DualSystem::prefetch_row(int i) const {
  for (int a = 0; a < 4; ++a)
    if (free_slots_[i] >> a & 1) {
      const int p = particles_[i][a];
      const char* lo = reinterpret_cast<const char*>(grad_at_.data() + inc_start_[p]);
      const char* hi = reinterpret_cast<const char*>(grad_at_.data() + inc_start_[p + 1]);
      for (const char* c = lo; c < hi; c += 64) __builtin_prefetch(c);
    }
}

void DualSystem::fill(const ConstraintState& s, const Eigen::VectorXd& alpha_tilde) {
  const Eigen::VectorXd& w = prob_.particles.w;
  fill_values(s, alpha_tilde, [&](int p, const Eigen::Vector3d& ga, const Eigen::Vector3d& gb) { return w[p] * ga.dot(gb); });
}

void DualSystem::fill(const ConstraintState& s, const Eigen::VectorXd& alpha_tilde, const Eigen::Matrix3Xd& w_dof) {
  fill_values(s, alpha_tilde, [&](int p, const Eigen::Vector3d& ga, const Eigen::Vector3d& gb) {
    return ga.dot(w_dof.col(p).cwiseProduct(gb));
  });
}

template <class Dot>
void DualSystem::fill_values(const ConstraintState& s, const Eigen::VectorXd& alpha_tilde, Dot&& dot) {
  const int m = rows();
  const int* outer = A_.outerIndexPtr();
  double* val = A_.valuePtr();
  // The gradients into particle order: read in constraint order, written to each slot's incidence.
#pragma omp parallel for schedule(static)
  for (int j = 0; j < m; ++j)
    for (int a = 0; a < 4; ++a)
      if (slot_inc_[4 * j + a] >= 0) grad_at_[slot_inc_[4 * j + a]] = s.grad[j][a];
  // Row i in one pass: zero it, add each term in the order of its slots (so A_ij sums its shared
  // particles in the same order for every fill), then α̃ on the diagonal.
  constexpr int kAhead = 2;
#pragma omp parallel for schedule(static)
  for (int i = 0; i < m; ++i) {
    if (i + kAhead < m) prefetch_row(i + kAhead);
    double* row = val + outer[i];
    std::fill(row, val + outer[i + 1], 0.0);
    const int* pos = term_pos_.data() + term_start_[i];
    for (int a = 0; a < 4; ++a) {
      if (!(free_slots_[i] >> a & 1)) continue;
      const int p = particles_[i][a];
      const Eigen::Vector3d& ga = s.grad[i][a];
      for (int k = inc_start_[p]; k < inc_start_[p + 1]; ++k) row[*pos++] += dot(p, ga, grad_at_[k]);
    }
    val[diag_[i]] += alpha_tilde[i];
  }
}

// One particle per thread (a gather): no two threads write one output.
template <class Op>
void DualSystem::gather_gradT(const ConstraintState& s, const Eigen::VectorXd& y, Eigen::Matrix3Xd& out, Op op) const {
  const int n = prob_.particles.size();
  out.resize(3, n);
#pragma omp parallel for schedule(static)
  for (int p = 0; p < n; ++p) {
    Eigen::Vector3d acc = Eigen::Vector3d::Zero();
    for (int k = inc_start_[p]; k < inc_start_[p + 1]; ++k)
      acc += op(s.grad[inc_[k].constraint][inc_[k].slot]) * y[inc_[k].constraint];
    out.col(p) = acc;
  }
}

void DualSystem::apply_gradT(const ConstraintState& s, const Eigen::VectorXd& y, Eigen::Matrix3Xd& out) const {
  gather_gradT(s, y, out, [](const Eigen::Vector3d& g) { return g; });
}

void DualSystem::apply_abs_gradT(const ConstraintState& s, const Eigen::VectorXd& y, Eigen::Matrix3Xd& out) const {
  gather_gradT(s, y, out, [](const Eigen::Vector3d& g) { return Eigen::Vector3d(g.cwiseAbs()); });
}

void DualSystem::apply_minv_gradT(const ConstraintState& s, const Eigen::VectorXd& y, Eigen::Matrix3Xd& out) const {
  apply_gradT(s, y, out);
  const Eigen::VectorXd& w = prob_.particles.w;
#pragma omp parallel for schedule(static)
  for (int p = 0; p < static_cast<int>(out.cols()); ++p) out.col(p) *= w[p];
}

}  // namespace xb

namespace xb {

void DualSystem::apply_minv_gradT(const ConstraintState& s, const Eigen::VectorXd& y, const Eigen::Matrix3Xd& w_dof,
                                  Eigen::Matrix3Xd& out) const {
  apply_gradT(s, y, out);
  const Eigen::VectorXd& w = prob_.particles.w;
#pragma omp parallel for schedule(static)
  for (int p = 0; p < static_cast<int>(out.cols()); ++p)
    out.col(p) = w[p] > 0 ? Eigen::Vector3d(out.col(p).cwiseProduct(w_dof.col(p))) : Eigen::Vector3d::Zero();
}

}  // namespace xb
