// The paper's scenes: builders (counts, pins, colliders), variants, stability checks,
// mesh output, and every scene × every method on a tiny size ending ok or with an honest status.
#include "harness/cli/report.hpp"
#include "harness/cli/run_setup.hpp"
#include "harness/io/run_record.hpp"
#include "harness/io/mesh_writer.hpp"
#include "harness/sim/stability.hpp"
#include "harness/sim/simulation.hpp"
#include "core/error.hpp"
#include "problems/scene.hpp"
#include "solvers/linear_solver.hpp"

#include <gtest/gtest.h>
#include <mpi.h>

#include <filesystem>
#include <fstream>
#include <set>

namespace fs = std::filesystem;
using namespace xb;

namespace {
// hypre and MueLu need MPI; initialised once for the test process unless another test file's
// environment did it already.
class MpiEnv : public ::testing::Environment {
 public:
  void SetUp() override {
    int done = 0;
    MPI_Initialized(&done);
    if (!done) owned_ = MPI_Init(nullptr, nullptr) == MPI_SUCCESS;
  }
  void TearDown() override {
    int done = 0;
    MPI_Finalized(&done);
    if (owned_ && !done) MPI_Finalize();
  }

 private:
  bool owned_ = false;
};
[[maybe_unused]] ::testing::Environment* const mpi_env = ::testing::AddGlobalTestEnvironment(new MpiEnv);

const std::set<std::string> paper_scenes = {"squash", "twist_bar", "cantilever", "cloth_hang", "ball_drop", "mass_chain"};
// Tournier et al. 2015's heavy-end-mass chains.
const std::set<std::string> chain_scenes = {"heavy_rope", "pendulum"};

Params tiny(const std::string& scene, std::vector<std::string> sets = {}) {
  // Small enough for every method in well under a second per run.
  // threads=1: OpenMP barriers spin badly on a shared, oversubscribed machine.
  std::vector<std::string> s = {"frames=2", "max_iterations=15", "threads=1"};
  if (scene == "squash" || scene == "ball_drop") s.push_back("resolution=4");
  if (scene == "twist_bar" || scene == "cantilever") s.insert(s.end(), {"resolution=2", "aspect=3"});
  if (scene == "cloth_hang") s.push_back("resolution=6");
  if (scene == "mass_chain") s.push_back("resolution=12");
  s.insert(s.end(), sets.begin(), sets.end());
  return resolve_params(scene, s);
}
}  // namespace

TEST(Scenes, AllSixAreListed) {
  const auto names = scene_names();
  for (const auto& s : paper_scenes) EXPECT_NE(std::find(names.begin(), names.end(), s), names.end()) << s;
}

TEST(Scenes, SquashCollapsesToMinimumY) {
  const Params p = resolve_params("squash", {"resolution=6", "threads=1"});
  EXPECT_EQ(p.stiffness, 1e9);
  EXPECT_EQ(p.dt, 1e-2);
  EXPECT_EQ(p.gravity, 0.0);
  EXPECT_EQ(p.rtol, 1e-2);
  EXPECT_EQ(p.atol, 1e-4);
  const Problem prob = build_problem(p);
  EXPECT_GT(prob.tets.size(), 0u);
  EXPECT_EQ(prob.distance.size(), 0u);
  EXPECT_TRUE(prob.planes.empty());
  EXPECT_EQ(prob.particles.x.row(1).maxCoeff(), prob.particles.x.row(1).minCoeff());
  EXPECT_NEAR(prob.particles.x.row(1).minCoeff(), -0.5, 0.1);  // the ball's bottom
  EXPECT_EQ(prob.particles.w.minCoeff(), 1.0);                  // nothing pinned
  EXPECT_EQ(count_inverted_tets(prob, prob.particles.x), static_cast<int>(prob.tets.size()));  // all flat
  // The rest volume is the ball's: 1/(μ V) compliances sum up consistently.
  double V = 0;
  for (double v : prob.tets.rest_volume) V += v;
  EXPECT_NEAR(V, M_PI / 6, 0.3 * M_PI / 6);
}

TEST(Scenes, TwistBarIsTwistedEndToEnd) {
  const Params p = resolve_params("twist_bar", {"resolution=2", "aspect=3"});
  const Problem prob = build_problem(p);
  EXPECT_EQ(prob.tets.size(), 6u * 6 * 2 * 2);
  EXPECT_EQ(prob.gravity.norm(), 0.0);
  EXPECT_EQ(prob.particles.w.minCoeff(), 1.0);
  // Each cross-section is rotated about the bar's axis by twist·x/L against the untwisted bar.
  const Problem flat = build_problem(resolve_params("twist_bar", {"resolution=2", "aspect=3", "twist=0"}));
  const auto& x = prob.particles.x;
  const auto& x0 = flat.particles.x;
  const double L = x0.row(0).maxCoeff(), c = p.size / 2;
  for (int i = 0; i < prob.particles.size(); ++i) {
    const double a = p.twist * x0(0, i) / L;
    EXPECT_NEAR(x(0, i), x0(0, i), 1e-15);
    EXPECT_NEAR(x(1, i), c + std::cos(a) * (x0(1, i) - c) - std::sin(a) * (x0(2, i) - c), 1e-12);
    EXPECT_NEAR(x(2, i), c + std::sin(a) * (x0(1, i) - c) + std::cos(a) * (x0(2, i) - c), 1e-12);
  }
  EXPECT_NEAR(p.twist, M_PI / 2, 1e-15);
  // Tets near the twisted end are sheared: C > 0 for most of them.
  ConstraintState s;
  evaluate_constraints(prob, prob.particles.x, s);
  EXPECT_GT(s.C.maxCoeff(), 0.1);
  EXPECT_EQ(count_inverted_tets(prob, prob.particles.x), 0);
}

TEST(Scenes, CantileverPinsTheLeftOnePercent) {
  const Params p = resolve_params("cantilever", {"resolution=2", "aspect=3"});
  const Problem prob = build_problem(p);
  int pinned = 0;
  for (int i = 0; i < prob.particles.size(); ++i) {
    const bool left = prob.particles.x(0, i) == 0.0;
    EXPECT_EQ(prob.particles.w[i] == 0, left) << i;
    pinned += left;
  }
  EXPECT_EQ(pinned, 3 * 3);  // the x = 0 face of a 2×2 cross-section
  EXPECT_EQ(prob.gravity.y(), -9.8);
  EXPECT_TRUE(prob.planes.empty());
}

TEST(Scenes, OnlyBallDropHasACollider) {
  for (const auto& s : paper_scenes) {
    const Problem prob = build_problem(tiny(s));
    EXPECT_EQ(prob.planes.size(), s == "ball_drop" ? 1u : 0u) << s;
  }
  const Problem ball = build_problem(tiny("ball_drop"));
  EXPECT_EQ(ball.planes[0].height, 0.0);
  EXPECT_NEAR(ball.particles.x.row(1).minCoeff(), 0.01, 1e-12);
}

TEST(Scenes, MassChainGradesMassesUpToTheRatio) {
  const Params p = resolve_params("mass_chain", {"resolution=10", "mass_ratio=1e4"});
  const Problem prob = build_problem(p);
  ASSERT_EQ(prob.particles.size(), 11);
  EXPECT_EQ(prob.distance.size(), 10u);
  EXPECT_EQ(prob.tets.size(), 0u);
  EXPECT_EQ(prob.particles.w[0], 0.0);
  for (int i = 1; i < 11; ++i) {
    const double m = 1 / prob.particles.w[i], s = i / 10.0;
    EXPECT_NEAR(m, 1 + (1e4 - 1) * s * s, 1e-9 * m);
  }
}

// The end-mass chains: pinned at the origin, straight at `angle` off the downward vertical, links
// of size/resolution, only the last particle heavy (mass_ratio, the variants included).
TEST(Scenes, EndMassChainsHangAHeavyLastParticle) {
  const auto names = scene_names();
  for (const auto& s : chain_scenes) {
    EXPECT_NE(std::find(names.begin(), names.end(), s), names.end()) << s;
    const Params p = resolve_params(s, {});
    EXPECT_NEAR(p.dt, 1.0 / 60, 1e-15) << s;
    EXPECT_EQ(p.mass_ratio, 100.0) << s;
    const Problem prob = build_problem(p);
    const int n = prob.particles.size();
    ASSERT_EQ(n, p.resolution + 1) << s;
    EXPECT_EQ(prob.particles.w[0], 0.0);
    EXPECT_EQ(prob.particles.x.col(0), Eigen::Vector3d::Zero());
    const Eigen::Vector3d dir(std::sin(p.angle), -std::cos(p.angle), 0);
    for (int i = 1; i < n; ++i) {
      EXPECT_NEAR((prob.particles.x.col(i) - i * p.size / p.resolution * dir).norm(), 0, 1e-12) << s << " " << i;
      EXPECT_EQ(1 / prob.particles.w[i], i + 1 < n ? p.particle_mass : 100 * p.particle_mass) << s << " " << i;
      EXPECT_EQ(prob.distance.compliance[i - 1], p.compliance);
    }
    EXPECT_GT(std::abs(std::sin(p.angle)), 0.25) << s << ": released off the vertical, so it swings";
    const Problem heavy = build_problem(resolve_params(s, {"variant=mass_ratio_1e4"}));
    EXPECT_EQ(1 / heavy.particles.w[n - 1], 1e4 * p.particle_mass);
    EXPECT_EQ(1 / heavy.particles.w[n - 2], p.particle_mass);  // no i² grading
    for (double a : build_problem(resolve_params(s, {"variant=mu1e12"})).distance.compliance) EXPECT_EQ(a, 1e-12);
    for (double a : build_problem(resolve_params(s, {"variant=rigid"})).distance.compliance) EXPECT_EQ(a, 0.0);
    EXPECT_NEAR(resolve_params(s, {"variant=dt_30hz"}).dt, 1.0 / 30, 1e-15);
  }
  const Problem nd = build_problem(resolve_params("heavy_rope", {"variant=near_degenerate"}));
  EXPECT_NEAR(nd.distance.rest_length[5], 1e-3 * nd.distance.rest_length[4], 1e-15);
  EXPECT_THROW(build_problem(resolve_params("pendulum", {"variant=near_degenerate"})), Error);  // 5 links: none to shorten
  EXPECT_THROW(build_problem(resolve_params("mass_chain", {"angle=0.3"})), Error);
}

TEST(Variants, SetImpliedKeysAndActOnTheProblem) {
  EXPECT_NEAR(resolve_params("cloth_hang", {"variant=dt_30hz"}).dt, 1.0 / 30, 1e-15);
  EXPECT_EQ(resolve_params("squash", {"variant=mu1e12"}).stiffness, 1e12);
  EXPECT_EQ(resolve_params("squash", {"variant=mass_ratio_1e4"}).mass_ratio, 1e4);
  // An explicit key after the variant wins.
  EXPECT_EQ(resolve_params("cloth_hang", {"variant=dt_30hz", "dt=0.01"}).dt, 0.01);
  EXPECT_THROW(resolve_params("cloth_hang", {"variant=squishy"}), Error);

  const Problem rigid = build_problem(tiny("twist_bar", {"variant=rigid"}));
  for (double a : rigid.tets.compliance) EXPECT_EQ(a, 0.0);
  const Problem rigid_cloth = build_problem(tiny("cloth_hang", {"variant=rigid"}));
  for (double a : rigid_cloth.distance.compliance) EXPECT_EQ(a, 0.0);

  // near_degenerate: some rest volumes 1e-3 of the others, none inverted.
  const Problem nd = build_problem(tiny("cantilever", {"variant=near_degenerate", "resolution=3"}));
  const double vmax = *std::max_element(nd.tets.rest_volume.begin(), nd.tets.rest_volume.end());
  const double vmin = *std::min_element(nd.tets.rest_volume.begin(), nd.tets.rest_volume.end());
  EXPECT_GT(vmin, 0);
  EXPECT_LT(vmin / vmax, 1e-2);
  const Problem ndc = build_problem(tiny("cloth_hang", {"variant=near_degenerate"}));
  const double lmin = *std::min_element(ndc.distance.rest_length.begin(), ndc.distance.rest_length.end());
  EXPECT_GT(lmin, 0);
}

TEST(Stability, BoundsScaleWithTheScene) {
  const Params p = tiny("ball_drop");
  const Problem prob = build_problem(p);
  const StabilityBounds b = stability_bounds(prob, p);
  const double L = (prob.particles.x.rowwise().maxCoeff() - prob.particles.x.rowwise().minCoeff()).norm();
  EXPECT_NEAR(b.max_speed, 10 * (L / p.dt + 9.8 * p.dt * p.frames), 1e-9 * b.max_speed);
  EXPECT_NEAR(b.max_extent, 100 * L + 9.8 * std::pow(p.dt * p.frames, 2), 1e-9 * b.max_extent);
}

TEST(Stability, RunawayAndNanAreReported) {
  const Params p = tiny("cloth_hang");
  Problem prob = build_problem(p);
  StabilityMonitor mon(prob, p);
  std::string st, msg;
  Particles P = prob.particles;
  EXPECT_TRUE(mon.check(P, 0, 0, st, msg));
  P.v(1, 3) = 2 * mon.bounds().max_speed;
  EXPECT_FALSE(mon.check(P, 1, 0, st, msg));
  EXPECT_EQ(st, "diverged");
  EXPECT_NE(msg.find("speed"), std::string::npos) << msg;
  P.v.setZero();
  P.x(0, 5) = mon.bounds().max_extent;
  EXPECT_FALSE(mon.check(P, 1, 0, st, msg));
  EXPECT_EQ(st, "diverged");
  EXPECT_NE(msg.find("bounding-box"), std::string::npos) << msg;
  P.x(0, 5) = std::nan("");
  EXPECT_FALSE(mon.check(P, 2, 0, st, msg));
  EXPECT_EQ(st, "nan");
  EXPECT_TRUE(mon.inverted_tets().empty());  // cloth: no tets, no count
}

// Runs that blow up end with a failure status and a message, not a crash:
// over-relaxed Jacobi (ωJ = 2 with 6 constraints per particle) makes the dual residual explode;
// ω = 2 and dt = 1 s on a rigid chain of mass ratio 1e8 flings the chain kilometres away.
TEST(Stability, BlowUpEndsWithAStatus) {
  const Params p = tiny("cloth_hang", {"xpbd.jacobi_relaxation=2", "max_iterations=100"});
  const RunResult r = run_simulation(build_problem(p), p, "xpbd-jacobi");
  EXPECT_EQ(r.status, "diverged") << r.message;
  EXPECT_NE(r.message.find("dual residual grew"), std::string::npos) << r.message;

  const Params q = tiny("mass_chain", {"omega=2", "dt=1", "compliance=0", "mass_ratio=1e8", "frames=20", "max_iterations=50"});
  const RunResult rq = run_simulation(build_problem(q), q, "cholmod");
  EXPECT_EQ(rq.status, "diverged") << rq.message;
  EXPECT_NE(rq.message.find("runaway"), std::string::npos) << rq.message;
}

TEST(Stability, InvertedTetsAreLoggedPerSubstepForTetScenesOnly) {
  const Params p = tiny("squash", {"frames=3"});
  const RunResult r = run_simulation(build_problem(p), p, "cholmod");
  ASSERT_TRUE(r.arrays.count("inverted_tets"));
  EXPECT_EQ(r.arrays.at("inverted_tets").size(), 3u);
  EXPECT_FALSE(r.arrays.count("distance_edges"));
  const Params c = tiny("cloth_hang");
  const RunResult rc = run_simulation(build_problem(c), c, "xpbd-gs");
  EXPECT_FALSE(rc.arrays.count("inverted_tets"));
  ASSERT_TRUE(rc.arrays.count("distance_edges"));
  EXPECT_EQ(rc.arrays.at("distance_edges").size(), 2 * rc.arrays.at("distance_rest_length").size());
}

// Every scene with every available method on a tiny size: ok or an honest status, never an
// exception; a failure status always carries a message.
TEST(Scenes, EverySceneRunsWithEveryMethod) {
  const std::set<std::string> honest = {"ok", "max_iterations", "diverged", "nan", "breakdown"};
  std::set<std::string> scenes = paper_scenes;
  scenes.insert(chain_scenes.begin(), chain_scenes.end());
  for (const auto& s : scenes) {
    const Params p = tiny(s);
    const Problem prob = build_problem(p);
    for (const auto& m : methods()) {
      if (!m.available) continue;
      RunResult r;
      ASSERT_NO_THROW(r = run_simulation(prob, p, m.name)) << s << " " << m.name;
      EXPECT_TRUE(honest.count(r.status)) << s << " " << m.name << ": " << r.status << " " << r.message;
      if (r.status != "ok") {
        EXPECT_FALSE(r.message.empty()) << s << " " << m.name;
      }
      EXPECT_GT(r.log.dual_residual.size(), 0u);
    }
  }
}

TEST(MeshWriter, PlyHeaderAndSize) {
  const Params p = tiny("ball_drop");
  const Problem prob = build_problem(p);
  const std::string dir = (fs::temp_directory_path() / ("xb_ply_" + std::to_string(::getpid()))).string();
  const std::string path = frame_ply_path(dir, "ball", 3);
  EXPECT_EQ(fs::path(path).filename(), "ball_0003.ply");
  write_ply(path, prob, prob.particles.x);
  std::ifstream in(path, std::ios::binary);
  std::string header, line;
  while (std::getline(in, line) && line != "end_header") header += line + "\n";
  EXPECT_NE(header.find("element vertex " + std::to_string(prob.particles.size())), std::string::npos);
  EXPECT_NE(header.find("element face " + std::to_string(prob.surface.size())), std::string::npos);
  const auto body = fs::file_size(path) - (header.size() + std::string("end_header\n").size());
  EXPECT_EQ(body, 12u * prob.particles.size() + 13u * prob.surface.size());
  // A chain has no surface: its links are PLY edges.
  const Problem chain = build_problem(tiny("mass_chain"));
  write_ply(dir + "/chain.ply", chain, chain.particles.x, false);
  std::ifstream c(dir + "/chain.ply");
  std::string all((std::istreambuf_iterator<char>(c)), {});
  EXPECT_NE(all.find("element edge 12"), std::string::npos);
  fs::remove_all(dir);
}
