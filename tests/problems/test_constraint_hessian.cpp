// Constraint Hessians against central finite differences of the gradients (at rest as defined,
// stretched, compressed, near-inverted, inverted, randomly rotated), the ARAP eigensystem against
// a finite-difference F-space Hessian, and the closed-form PSD projections against the numeric
// eigen-projection.
#include "problems/constraint_hessian.hpp"
#include "problems/constraints.hpp"

#include <gtest/gtest.h>

#include <random>

using namespace xb;

namespace {

std::mt19937 rng(7);
double uni(double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng); }
Eigen::Vector3d rand3(double s = 1.0) { return {uni(-s, s), uni(-s, s), uni(-s, s)}; }

Eigen::Matrix3d random_rotation() {
  Eigen::Quaterniond q(uni(-1, 1), uni(-1, 1), uni(-1, 1), uni(-1, 1));
  return q.normalized().toRotationMatrix();
}

double max_abs(const Eigen::MatrixXd& A) { return A.cwiseAbs().maxCoeff(); }

// A tet with a random rest shape and positions x_a = R·F0·X_a + t, and its Dm⁻¹.
struct Tet {
  std::array<Eigen::Vector3d, 4> x;
  Eigen::Matrix3d Dm_inv;
};
Tet make_tet(const Eigen::Vector3d& sigma) {
  std::array<Eigen::Vector3d, 4> X = {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(0, 1, 0),
                                      Eigen::Vector3d(0, 0, 1)};
  for (auto& v : X) v += rand3(0.2);
  Eigen::Matrix3d Dm;
  for (int c = 0; c < 3; ++c) Dm.col(c) = X[c + 1] - X[0];
  if (Dm.determinant() < 0) std::swap(X[1], X[2]);
  for (int c = 0; c < 3; ++c) Dm.col(c) = X[c + 1] - X[0];
  const Eigen::Matrix3d F0 = random_rotation() * sigma.asDiagonal() * random_rotation().transpose();
  const Eigen::Matrix3d R = random_rotation();
  const Eigen::Vector3d t = rand3();
  Tet tet;
  for (int a = 0; a < 4; ++a) tet.x[a] = R * F0 * X[a] + t;
  tet.Dm_inv = Dm.inverse();
  return tet;
}

using Vec12 = Eigen::Matrix<double, 12, 1>;
Vec12 tet_gradient(const Vec12& x, const Eigen::Matrix3d& Dm_inv, double* C = nullptr) {
  std::array<Eigen::Vector3d, 4> g;
  const double c = tet_arap_constraint(x.segment<3>(0), x.segment<3>(3), x.segment<3>(6), x.segment<3>(9), Dm_inv, &g);
  if (C) *C = c;
  Vec12 out;
  for (int a = 0; a < 4; ++a) out.segment<3>(3 * a) = g[a];
  return out;
}
Vec12 pack(const Tet& t) {
  Vec12 x;
  for (int a = 0; a < 4; ++a) x.segment<3>(3 * a) = t.x[a];
  return x;
}

// Central differences of a gradient field f: R^N → R^N, column by column.
template <int N, class F>
Eigen::Matrix<double, N, N> fd_jacobian(const Eigen::Matrix<double, N, 1>& x, F&& f, double h) {
  Eigen::Matrix<double, N, N> J;
  for (int i = 0; i < N; ++i) {
    Eigen::Matrix<double, N, 1> e = Eigen::Matrix<double, N, 1>::Zero();
    e[i] = h;
    J.col(i) = (f(x + e) - f(x - e)) / (2 * h);
  }
  return J;
}

// Singular values of the cases: stretched, compressed, mixed, near-inverted, inverted.
const std::vector<Eigen::Vector3d> cases = {
    {1.5, 1.3, 1.2}, {0.6, 0.7, 0.8}, {1.4, 0.9, 0.6}, {1.1, 0.9, 0.02}, {1.2, 0.8, -0.3}, {0.9, 0.5, -0.4}};

}  // namespace

TEST(DistanceHessian, MatchesFiniteDifferencesOfTheGradient) {
  for (int trial = 0; trial < 30; ++trial) {
    const Eigen::Vector3d p = rand3(), q = rand3();
    Eigen::Matrix<double, 6, 1> x;
    x << p, q;
    auto grad = [](const Eigen::Matrix<double, 6, 1>& y) {
      Eigen::Vector3d gp, gq;
      distance_constraint(y.head<3>(), y.tail<3>(), 0.5, &gp, &gq);
      Eigen::Matrix<double, 6, 1> g;
      g << gp, gq;
      return g;
    };
    const Matrix6d H = distance_hessian(p, q);
    const Matrix6d fd = fd_jacobian<6>(x, grad, 1e-6);
    EXPECT_LE(max_abs(H - fd), 1e-6 * max_abs(H)) << "trial " << trial;
    EXPECT_EQ(H, H.transpose());
    // The Newton block (∇C∇Cᵀ + C∇²C)/α̃ against differences of C∇C/α̃, stretched or compressed.
    const double rest = (p - q).norm() * (trial % 2 ? 1.3 : 0.7), at = 1e-3;
    auto egrad = [&](const Eigen::Matrix<double, 6, 1>& y) {
      Eigen::Vector3d gp, gq;
      const double C = distance_constraint(y.head<3>(), y.tail<3>(), rest, &gp, &gq);
      Eigen::Matrix<double, 6, 1> g;
      g << gp, gq;
      return Eigen::Matrix<double, 6, 1>(C / at * g);
    };
    const Matrix6d He = distance_energy_hessian(p, q, rest, at, Projection::none);
    EXPECT_LE(max_abs(He - fd_jacobian<6>(x, egrad, 1e-6)), 1e-6 * max_abs(He));
  }
  // Coincident points: no direction, no force, no Hessian (the documented convention).
  EXPECT_EQ(distance_hessian({1, 2, 3}, {1, 2, 3}), Matrix6d::Zero());
}

TEST(TetArapHessian, MatchesFiniteDifferencesOfTheGradient) {
  for (const auto& sigma : cases)
    for (int trial = 0; trial < 5; ++trial) {
      const Tet t = make_tet(sigma);
      const Matrix12d H = tet_arap_hessian(t.x[0], t.x[1], t.x[2], t.x[3], t.Dm_inv);
      const Matrix12d fd = fd_jacobian<12>(pack(t), [&](const Vec12& y) { return tet_gradient(y, t.Dm_inv); }, 1e-6);
      EXPECT_LE(max_abs(H - fd), 2e-6 * max_abs(H)) << "sigma " << sigma.transpose() << " trial " << trial;
      EXPECT_EQ(H, H.transpose());
      // The energy Hessian ∇²Ψ/α̃ against differences of C∇C/α̃.
      const double at = 0.25;
      const Matrix12d He = tet_energy_hessian(t.x[0], t.x[1], t.x[2], t.x[3], t.Dm_inv, at, Projection::none);
      const Matrix12d fde = fd_jacobian<12>(
          pack(t),
          [&](const Vec12& y) {
            double C;
            const Vec12 g = tet_gradient(y, t.Dm_inv, &C);
            return Vec12(C / at * g);
          },
          1e-6);
      EXPECT_LE(max_abs(He - fde), 2e-6 * max_abs(He)) << "sigma " << sigma.transpose();
    }
}

// At rest C = ‖F − R‖ has a kink: ∇C and ∇²C are zero by convention, while Ψ = ½C² is smooth and
// its Hessian (twist 0, the rest 1/α̃ in F-space) matches differences of C∇C.
TEST(TetArapHessian, AtRestAsDefined) {
  const Tet t = make_tet({1, 1, 1});
  EXPECT_EQ(tet_arap_hessian(t.x[0], t.x[1], t.x[2], t.x[3], t.Dm_inv), Matrix12d::Zero());
  EXPECT_EQ(tet_geometric_stiffness(t.x[0], t.x[1], t.x[2], t.x[3], t.Dm_inv, -3.0, Projection::none), Matrix12d::Zero());
  const double at = 2.0;
  const Matrix12d He = tet_energy_hessian(t.x[0], t.x[1], t.x[2], t.x[3], t.Dm_inv, at, Projection::none);
  const Matrix12d fde = fd_jacobian<12>(
      pack(t),
      [&](const Vec12& y) {
        double C;
        const Vec12 g = tet_gradient(y, t.Dm_inv, &C);
        return Vec12(C / at * g);
      },
      1e-6);
  EXPECT_LE(max_abs(He - fde), 1e-6 * max_abs(He));
  const ArapEigensystem es = arap_eigensystem(Eigen::Matrix3d::Identity());
  for (int k = 3; k < 6; ++k) EXPECT_NEAR(es.psi[k], 0.0, 1e-15);  // twists: 1 − 2/2
}

// The closed-form eigensystem of ∇²_F Ψ (twist 1 − 2/(σᵢ + σⱼ), flip and scale 1) against central
// differences of ∇_F Ψ = F − R(F), with orthonormal modes.
TEST(TetArapHessian, ClosedFormEigensystemOfPsi) {
  for (const auto& sigma : cases) {
    const Eigen::Matrix3d F = random_rotation() * sigma.asDiagonal() * random_rotation().transpose();
    const ArapEigensystem es = arap_eigensystem(F);
    Matrix9d Q;
    for (int k = 0; k < 9; ++k) Q.col(k) = Eigen::Map<const Eigen::Matrix<double, 9, 1>>(es.mode[k].data());
    EXPECT_LE(max_abs(Q.transpose() * Q - Matrix9d::Identity()), 1e-12);
    auto dpsi = [](const Eigen::Matrix<double, 9, 1>& f) {
      const Eigen::Map<const Eigen::Matrix3d> G(f.data());
      Eigen::Matrix3d U, V;
      Eigen::Vector3d s;
      svd_rv(G, U, s, V);
      const Eigen::Matrix3d D = G - U * V.transpose();
      return Eigen::Matrix<double, 9, 1>(Eigen::Map<const Eigen::Matrix<double, 9, 1>>(D.data()));
    };
    const Matrix9d fd = fd_jacobian<9>(Eigen::Map<const Eigen::Matrix<double, 9, 1>>(F.data()), dpsi, 1e-6);
    const Matrix9d H = tet_modes_to_F(es, es.psi);
    EXPECT_LE(max_abs(H - fd), 1e-6 * max_abs(H)) << sigma.transpose();
    // ∇_F C lies along scale mode 0 (ĝ), where ∇²_F C has its zero eigenvalue.
    Eigen::Matrix3d U, V;
    Eigen::Vector3d s;
    svd_rv(F, U, s, V);
    EXPECT_LE((es.mode[0] - (F - U * V.transpose()) / es.C).norm(), 1e-12);
    EXPECT_EQ(es.c[0], 0.0);
  }
}

// The sign convention: G = −λ∇²C unprojected, and at λ = −C/α̃ the Gauss–Newton part plus G is
// the Newton block, ∇C∇Cᵀ/α̃ + G = (∇C∇Cᵀ + C∇²C)/α̃ = H.
TEST(GeometricStiffness, SignConventionAndNewtonSplit) {
  const double at = 0.05;
  for (const auto& sigma : cases) {
    const Tet t = make_tet(sigma);
    double C;
    const Vec12 g = tet_gradient(pack(t), t.Dm_inv, &C);
    const double lambda = -C / at;
    const Matrix12d G = tet_geometric_stiffness(t.x[0], t.x[1], t.x[2], t.x[3], t.Dm_inv, lambda, Projection::none);
    const Matrix12d hess = tet_arap_hessian(t.x[0], t.x[1], t.x[2], t.x[3], t.Dm_inv);
    EXPECT_LE(max_abs(G + lambda * hess), 1e-12 * max_abs(G)) << sigma.transpose();
    const Matrix12d H = tet_energy_hessian(t.x[0], t.x[1], t.x[2], t.x[3], t.Dm_inv, at, Projection::none);
    EXPECT_LE(max_abs(g * g.transpose() / at + G - H), 1e-12 * max_abs(H)) << sigma.transpose();
    for (Projection proj : {Projection::none, Projection::clamp}) {  // the diagonal alone is G's
      const Matrix12d Gp = tet_geometric_stiffness(t.x[0], t.x[1], t.x[2], t.x[3], t.Dm_inv, lambda, proj);
      EXPECT_LE(max_abs(tet_geometric_stiffness_diagonal(t.x[0], t.x[1], t.x[2], t.x[3], t.Dm_inv, lambda, proj) -
                        Gp.diagonal()),
                1e-12 * max_abs(G));
    }
  }
  for (double stretch : {0.5, 1.5}) {
    const Eigen::Vector3d p = rand3(), q = rand3();
    const double rest = (p - q).norm() / stretch, C = (p - q).norm() - rest, lambda = -C / at;
    const Matrix6d G = distance_geometric_stiffness(p, q, lambda, Projection::none);
    EXPECT_LE(max_abs(G + lambda * distance_hessian(p, q)), 1e-12 * max_abs(G));
    Eigen::Matrix<double, 6, 1> g;
    g << (p - q).normalized(), (q - p).normalized();
    EXPECT_LE(max_abs(g * g.transpose() / at + G - distance_energy_hessian(p, q, rest, at, Projection::none)), 1e-12 * max_abs(G));
    // Stretched (λ < 0 at the solution) the geometric stiffness is PSD; compressed it is not.
    const double min_eig = Eigen::SelfAdjointEigenSolver<Matrix6d>(G).eigenvalues().minCoeff();
    EXPECT_TRUE(stretch > 1 ? min_eig > -1e-12 * max_abs(G) : min_eig < -0.1 * max_abs(G)) << stretch;
  }
}

TEST(Projection, ClosedFormEqualsNumericEigenProjection) {
  for (Projection proj : {Projection::clamp, Projection::abs})
    for (const auto& sigma : cases)
      for (double lambda : {-2.0, 3.0}) {
        const Eigen::Matrix3d F = random_rotation() * sigma.asDiagonal() * random_rotation().transpose();
        const ArapEigensystem es = arap_eigensystem(F);
        Eigen::Matrix<double, 9, 1> g = -lambda * es.c, gp, e = es.psi / 0.5, ep;
        for (int k = 0; k < 9; ++k) gp[k] = project_eigenvalue(g[k], proj), ep[k] = project_eigenvalue(e[k], proj);
        Matrix9d G = tet_modes_to_F(es, g), E = tet_modes_to_F(es, e);
        const double gs = max_abs(G), esc = max_abs(E);  // the exact blocks' scales
        project_symmetric(G, proj);
        project_symmetric(E, proj);
        EXPECT_LE(max_abs(tet_modes_to_F(es, gp) - G), 1e-10 * gs) << sigma.transpose();
        EXPECT_LE(max_abs(tet_modes_to_F(es, ep) - E), 1e-10 * esc) << sigma.transpose();
        // Distance: the closed form against the numeric projection of the exact block.
        const Eigen::Vector3d p = rand3(), q = rand3();
        Matrix6d D = distance_geometric_stiffness(p, q, lambda, Projection::none);
        const double ds = max_abs(D);
        project_symmetric(D, proj);
        EXPECT_LE(max_abs(distance_geometric_stiffness(p, q, lambda, proj) - D), 1e-12 * ds);
        const double rest = (p - q).norm() * (lambda > 0 ? 1.5 : 0.5);
        Matrix6d N = distance_energy_hessian(p, q, rest, 0.1, Projection::none);
        const double ns = max_abs(N);
        project_symmetric(N, proj);
        EXPECT_LE(max_abs(distance_energy_hessian(p, q, rest, 0.1, proj) - N), 1e-12 * ns);
      }
}

TEST(Projection, EveryProjectedBlockIsPsd) {
  auto min_eig = [](const auto& A) { return Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(Eigen::MatrixXd(A)).eigenvalues().minCoeff(); };
  for (Projection proj : {Projection::clamp, Projection::abs})
    for (int trial = 0; trial < 60; ++trial) {
      const Tet t = make_tet(Eigen::Vector3d(uni(0.2, 2), uni(0.2, 2), uni(-1, 1)));
      const double lambda = uni(-5, 5);
      const Matrix12d G = tet_geometric_stiffness(t.x[0], t.x[1], t.x[2], t.x[3], t.Dm_inv, lambda, proj);
      const Matrix12d H = tet_energy_hessian(t.x[0], t.x[1], t.x[2], t.x[3], t.Dm_inv, 0.01, proj);
      EXPECT_GE(min_eig(G), -1e-12 * max_abs(G));
      EXPECT_GE(min_eig(H), -1e-12 * max_abs(H));
      const Eigen::Vector3d p = rand3(), q = rand3();
      const Matrix6d D = distance_geometric_stiffness(p, q, lambda, proj);
      const Matrix6d N = distance_energy_hessian(p, q, uni(0, 3), 0.01, proj);
      EXPECT_GE(min_eig(D), -1e-12 * max_abs(D));
      EXPECT_GE(min_eig(N), -1e-12 * max_abs(N));
    }
}

// Where the exact block is PSD already (stretched: every σᵢ + σⱼ ≥ 2, and λ < 0 as at a stretched
// solution), both projections return it unchanged.
TEST(Projection, LeavesAPsdBlockUnchanged) {
  for (Projection proj : {Projection::clamp, Projection::abs}) {
    const Tet t = make_tet({1.5, 1.3, 1.2});
    const double lambda = -2.0, at = 0.3;
    const auto G = [&](Projection p) { return tet_geometric_stiffness(t.x[0], t.x[1], t.x[2], t.x[3], t.Dm_inv, lambda, p); };
    const auto H = [&](Projection p) { return tet_energy_hessian(t.x[0], t.x[1], t.x[2], t.x[3], t.Dm_inv, at, p); };
    EXPECT_LE(max_abs(G(proj) - G(Projection::none)), 1e-14 * max_abs(G(Projection::none)));
    EXPECT_LE(max_abs(H(proj) - H(Projection::none)), 1e-14 * max_abs(H(Projection::none)));
    const Eigen::Vector3d p(0, 0, 0), q(1, 0.5, 0);
    EXPECT_EQ(distance_geometric_stiffness(p, q, lambda, proj), distance_geometric_stiffness(p, q, lambda, Projection::none));
    EXPECT_EQ(distance_energy_hessian(p, q, 0.5, at, proj), distance_energy_hessian(p, q, 0.5, at, Projection::none));
    // A numeric projection of a PSD matrix changes it only by rounding.
    Matrix12d A = H(Projection::none);
    project_symmetric(A, proj);
    EXPECT_LE(max_abs(A - H(Projection::none)), 1e-12 * max_abs(A));
  }
  // And the projection does act where the block is indefinite (a compressed distance, λ > 0).
  EXPECT_NE(distance_geometric_stiffness({0, 0, 0}, {1, 0, 0}, 2.0, Projection::clamp),
            distance_geometric_stiffness({0, 0, 0}, {1, 0, 0}, 2.0, Projection::none));
}

TEST(Projection, Names) {
  EXPECT_EQ(parse_projection("abs", "x"), Projection::abs);
  EXPECT_EQ(projection_name(Projection::clamp), "clamp");
  EXPECT_THROW(parse_projection("flip", "xpbd.projection"), std::exception);
}
