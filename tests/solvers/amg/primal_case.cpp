// The primal-form test systems of test_amg_primal.hpp.
#include "test_amg_primal.hpp"

#include "solvers/kernels.hpp"

namespace xb::test {

namespace {
// Free particle i → its index among the free particles (−1 when pinned).
std::vector<int> free_index(const Problem& prob) {
  std::vector<int> f(prob.particles.size(), -1);
  int k = 0;
  for (int i = 0; i < prob.particles.size(); ++i)
    if (prob.particles.w[i] > 0) f[i] = k++;
  return f;
}

SparseMatrix jacobian(const Problem& prob, const ConstraintState& st, const std::vector<int>& fidx, int nfree) {
  std::vector<Eigen::Triplet<double>> t;
  for (int j = 0; j < prob.num_constraints(); ++j) {
    const auto ps = prob.constraint_particles(j);
    for (int k = 0; k < 4; ++k)
      if (ps[k] >= 0 && fidx[ps[k]] >= 0)
        for (int d = 0; d < 3; ++d) t.emplace_back(j, 3 * fidx[ps[k]] + d, st.grad[j][k][d]);
  }
  SparseMatrix J(prob.num_constraints(), 3 * nfree);
  J.setFromTriplets(t.begin(), t.end());
  return J;
}

// One frame of dual XPBD with a direct solve (the harness's Algorithm 4, ω = 1, no colliders).
void dual_frame(Problem& prob, DualSystem& ds, LinearSolver& direct, double h, double gravity, int iterations) {
  Particles& P = prob.particles;
  const Eigen::Matrix3Xd x_old = P.x;
  for (int i = 0; i < P.size(); ++i)
    if (P.w[i] > 0) {
      P.x.col(i) += h * P.v.col(i);
      P.x(1, i) += h * h * gravity;
    }
  const Vector at = scaled_compliance(prob, h);
  Vector lambda = Vector::Zero(prob.num_constraints()), dl;
  ConstraintState st;
  Eigen::Matrix3Xd dx;
  for (int it = 0; it < iterations; ++it) {
    evaluate_constraints(prob, P.x, st);
    ds.fill(st, at);
    const Vector b = -(st.C + at.cwiseProduct(lambda));
    direct.setup(ds.A(), SetupKind::Values, {});
    direct.solve(b, dl);
    lambda += dl;
    ds.apply_minv_gradT(st, dl, dx);
    P.x += dx;
  }
  P.v = (P.x - x_old) / h;
}
}  // namespace

SparseMatrix primal_matrix(const Problem& prob, const Eigen::Matrix3Xd& x, double h, SparseMatrix* J_out) {
  const std::vector<int> fidx = free_index(prob);
  int nfree = 0;
  for (int v : fidx) nfree += v >= 0;
  ConstraintState st;
  evaluate_constraints(prob, x, st);
  const SparseMatrix J = jacobian(prob, st, fidx, nfree);
  const Vector at = scaled_compliance(prob, h);
  SparseMatrix JtW = J.transpose() * at.cwiseInverse().asDiagonal();
  SparseMatrix K = JtW * J;
  Vector m(3 * nfree);
  for (int i = 0; i < prob.particles.size(); ++i)
    if (fidx[i] >= 0) m.segment<3>(3 * fidx[i]).setConstant(1.0 / prob.particles.w[i]);
  SparseMatrix M(3 * nfree, 3 * nfree);
  M.setIdentity();
  M = m.asDiagonal() * M;
  K = K + M;
  K.makeCompressed();
  if (J_out) *J_out = J;
  return K;
}

PrimalCase primal_case(const std::string& scene, const std::vector<std::pair<std::string, std::string>>& overrides,
                       int frames, int iterations) {
  Params p;
  load_scene_file(resolve_scene(scene), p);
  for (const auto& [k, v] : overrides) set_param(p, k, v, "test");
  PrimalCase c;
  c.prob = std::make_unique<Problem>(build_problem(p));
  Problem& prob = *c.prob;
  c.ds = std::make_unique<DualSystem>(prob);
  const double h = p.dt / p.substeps;
  auto direct = make_linear_solver("cholmod", p);
  {
    // CHOLMOD's analysis on A's pattern, with values (the first fill), so it factors an SPD matrix.
    ConstraintState st0;
    evaluate_constraints(prob, prob.particles.x, st0);
    c.ds->fill(st0, scaled_compliance(prob, p.dt / p.substeps));
    direct->setup(c.ds->A(), SetupKind::Structure, {});
  }
  for (int f = 0; f < frames; ++f) dual_frame(prob, *c.ds, *direct, h, p.gravity, 4);
  // The next frame's predicted state, then `iterations` outer iterations.
  Particles& P = prob.particles;
  for (int i = 0; i < P.size(); ++i)
    if (P.w[i] > 0) {
      P.x.col(i) += h * P.v.col(i);
      P.x(1, i) += h * h * p.gravity;
    }
  c.alpha_tilde = scaled_compliance(prob, h);
  Vector lambda = Vector::Zero(prob.num_constraints()), dl;
  ConstraintState st;
  Eigen::Matrix3Xd dx;
  for (int it = 0;; ++it) {
    evaluate_constraints(prob, P.x, st);
    c.ds->fill(st, c.alpha_tilde);
    c.b = -(st.C + c.alpha_tilde.cwiseProduct(lambda));
    if (it == iterations) break;
    direct->setup(c.ds->A(), SetupKind::Values, {});
    direct->solve(c.b, dl);
    lambda += dl;
    c.ds->apply_minv_gradT(st, dl, dx);
    P.x += dx;
  }
  c.K = primal_matrix(prob, P.x, h, &c.J);
  c.f = c.J.transpose() * c.b.cwiseQuotient(c.alpha_tilde);
  const std::vector<int> fidx = free_index(prob);
  const int nfree = static_cast<int>(c.K.rows() / 3);
  c.minv.resize(3 * nfree);
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (int i = 0; i < P.size(); ++i)
    if (fidx[i] >= 0) {
      c.minv.segment<3>(3 * fidx[i]).setConstant(P.w[i]);
      centroid += P.x.col(i);
    }
  centroid /= nfree;
  c.rigid.setZero(3 * nfree, 6);
  for (int i = 0; i < P.size(); ++i) {
    if (fidx[i] < 0) continue;
    const Eigen::Vector3d r = P.x.col(i) - centroid;
    for (int d = 0; d < 3; ++d) {
      c.rigid(3 * fidx[i] + d, d) = 1.0;
      c.rigid.block<3, 1>(3 * fidx[i], 3 + d) = Eigen::Vector3d::Unit(d).cross(r);
    }
  }
  return c;
}

RelativeResidual PrimalCase::dual_measure() const {
  const double nb = b.norm();
  return [this, nb](const Vector& r) {
    const Vector s = minv.cwiseProduct(r);
    return (J * s).norm() / nb;
  };
}

Vector PrimalCase::recover(const Vector& dx) const { return (b - J * dx).cwiseQuotient(alpha_tilde); }

const TwoStates& two_cloth_states() {
  static const TwoStates s{primal_case("cloth_hang", {{"resolution", "24"}}, 3, 0),
                           primal_case("cloth_hang", {{"resolution", "24"}}, 3, 1)};
  return s;
}

}  // namespace xb::test
