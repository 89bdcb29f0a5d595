// hypre BoomerAMG-PCG and MueLu-CG on assembled XPBD dual systems: the harness's tolerance
// checked by recomputing ‖b − Ax‖, values-only (lazy) setups, the parameter mapping, and the
// MPI case through the CLI (mpirun -np 2 against one process).
#include "external_mpi.hpp"

#include "harness/cli/report.hpp"
#include "harness/cli/run_setup.hpp"
#include "harness/io/run_record.hpp"
#include "harness/io/recorder.hpp"
#include "harness/sim/simulation.hpp"
#include "problems/dual_system.hpp"
#include "harness/params.hpp"
#include "problems/scene.hpp"
#include "solvers/mpi/distributed.hpp"
#include "solvers/kernels.hpp"
#include "solvers/linear_solver.hpp"

#include <gtest/gtest.h>
#include <hdf5.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <sys/wait.h>
#include <unistd.h>

using namespace xb;
namespace fs = std::filesystem;

namespace {

// A dual system from a scene with deformed positions (every constraint active).
struct System {
  Problem prob;
  std::unique_ptr<DualSystem> ds;
  ConstraintState s;
  Vector b;
  Eigen::VectorXd at;
};

void perturb(Problem& prob, double amount, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-amount, amount);
  for (int i = 0; i < prob.particles.size(); ++i)
    for (int d = 0; d < 3; ++d) prob.particles.x(d, i) += u(rng);
}

void refill(System& sys) {
  evaluate_constraints(sys.prob, sys.prob.particles.x, sys.s);
  sys.ds->fill(sys.s, sys.at);
  sys.b = -sys.s.C;  // the first outer iteration's right-hand side (λ = 0)
}

std::unique_ptr<System> make_system(const std::string& scene, int resolution, unsigned seed) {
  // The scene's own parameters (bar_hang: μ = 1e9 Pa, 0.2 m cross-section, prestretched).
  const Params p = resolve_params(scene, {"resolution=" + std::to_string(resolution)});
  auto sys = std::make_unique<System>();
  sys->prob = build_problem(p);
  perturb(sys->prob, 0.02 * p.size / resolution, seed);
  sys->ds = std::make_unique<DualSystem>(sys->prob);
  sys->at = scaled_compliance(sys->prob, p.dt / p.substeps);
  refill(*sys);
  return sys;
}

double true_relative_residual(const SparseMatrix& A, const Vector& x, const Vector& b) {
  Vector r;
  residual(A, x, b, r);
  return norm2(r) / norm2(b);
}

// Solve and check everything a LinearStats promises.
void check_solve(LinearSolver& solver, const SparseMatrix& A, const Vector& b, double tol, const std::string& what) {
  Vector x;
  const LinearStats st = solver.solve(b, x);
  ASSERT_EQ(st.status, LinearStatus::converged) << what << ": " << st.message;
  ASSERT_EQ(x.size(), b.size());
  const double rel = true_relative_residual(A, x, b);
  EXPECT_LE(rel, tol * 1.05) << what << " after " << st.iterations << " iterations";
  EXPECT_NEAR(st.final_relative_residual, rel, 1e-3 * rel + 1e-14) << what;
  EXPECT_GT(st.iterations, 0) << what;
  // One entry per iteration plus the initial residual ‖b‖ (zero start), time-stamped in order.
  ASSERT_EQ(st.residual_history.size(), static_cast<size_t>(st.iterations) + 1) << what;
  ASSERT_EQ(st.residual_time.size(), st.residual_history.size()) << what;
  EXPECT_NEAR(st.residual_history.front(), norm2(b), 1e-10 * norm2(b)) << what;
  EXPECT_LE(st.residual_history.back(), tol * norm2(b) * 1.0000001) << what;
  for (size_t k = 1; k < st.residual_time.size(); ++k) EXPECT_GE(st.residual_time[k], st.residual_time[k - 1]);
  EXPECT_GT(st.solve_time, 0) << what;
}

Params solver_params() {
  Params p;
  p.linear.tol = 1e-8;
  p.linear.max_iterations = 2000;
  return p;
}

}  // namespace

class ExternalSolver : public ::testing::TestWithParam<const char*> {};

TEST_P(ExternalSolver, ReachesHarnessToleranceOnClothAndBar) {
  const std::string name = GetParam();
  const Params p = solver_params();
  for (const auto& [scene, res] : {std::pair<std::string, int>{"cloth_hang", 24}, {"bar_hang", 4}}) {
    auto sys = make_system(scene, res, 11);
    auto solver = make_linear_solver(name, p);
    solver->setup(sys->ds->A(), SetupKind::Structure, SetupContext{});
    EXPECT_EQ(solver->last_setup_action(), "structure");
    check_solve(*solver, sys->ds->A(), sys->b, p.linear.tol, name + " on " + scene);
    const auto stats = solver->statistics();
    EXPECT_GE(stats.at("levels"), 2) << name << " on " << scene << ": no coarsening happened";
    EXPECT_GE(stats.at("operator_complexity"), 1.0);
    EXPECT_EQ(solver->array_statistics().at("level_rows").front(), sys->ds->rows());
  }
}

// After the positions move (same pattern, new values) a Values setup still solves the new
// system to the tolerance, and the lazy-setup action says what happened.
TEST_P(ExternalSolver, ValuesSetupAfterChangeSolvesNewSystem) {
  const std::string name = GetParam();
  Params p = solver_params();
  if (name == "hypre") p.hypre.reuse = "hierarchy";  // exercise the reuse path (default: none)
  if (name == "muelu") p.muelu.reuse = "RP";          // the dual form's strongest reuse (default: tP)
  p.amg.setup_interval = 3;
  auto sys = make_system("bar_hang", 4, 5);
  auto solver = make_linear_solver(name, p);
  solver->setup(sys->ds->A(), SetupKind::Structure, SetupContext{0, 0, 0});
  check_solve(*solver, sys->ds->A(), sys->b, p.linear.tol, name + " structure");
  const std::string reuse = name == "hypre" ? "reuse-hierarchy" : "reuse-RP";
  for (int frame : {1, 2, 3}) {
    perturb(sys->prob, 0.002 * 0.2 / 4, 100 + frame);
    refill(*sys);
    solver->setup(sys->ds->A(), SetupKind::Values, SetupContext{frame, 0, 1});
    // Frames 1, 2 reuse; frame 3 = setup_interval frames after the last build: rebuild.
    EXPECT_EQ(solver->last_setup_action(), frame < 3 ? reuse : "values") << name << " frame " << frame;
    check_solve(*solver, sys->ds->A(), sys->b, p.linear.tol, name + " values, frame " + std::to_string(frame));
  }
  const auto st = solver->statistics();
  EXPECT_EQ(st.at("setup_full"), 2);
  EXPECT_EQ(st.at("setup_reused"), 2);
}

INSTANTIATE_TEST_SUITE_P(External, ExternalSolver, ::testing::Values("hypre", "muelu"));

TEST(ExternalSolverParams, HypreChoicesMapToBoomerAmgCodes) {
  Params p;
  EXPECT_EQ(hypre_options(p).at("coarsen_type"), 10);  // HMIS default
  EXPECT_EQ(hypre_options(p).at("interp_type"), 6);    // ext+i
  EXPECT_EQ(hypre_options(p).at("relax_type"), 18);    // l1-Jacobi
  EXPECT_EQ(hypre_options(p).at("pcg_two_norm"), 1);
  const std::vector<std::pair<std::string, double>> coarsening = {{"HMIS", 10}, {"PMIS", 8}, {"Falgout", 6}};
  for (const auto& [k, v] : coarsening) {
    set_param(p, "hypre.coarsening", k, "test");
    EXPECT_EQ(hypre_options(p).at("coarsen_type"), v) << k;
  }
  const std::vector<std::pair<std::string, double>> interp = {
      {"ext+i", 6}, {"classical", 0}, {"direct", 3}, {"multipass", 4}};
  for (const auto& [k, v] : interp) {
    set_param(p, "hypre.interpolation", k, "test");
    EXPECT_EQ(hypre_options(p).at("interp_type"), v) << k;
  }
  const std::vector<std::pair<std::string, double>> relax = {
      {"l1-jacobi", 18}, {"jacobi", 0}, {"hgs", 6}, {"l1-gs", 8}, {"chebyshev", 16}};
  for (const auto& [k, v] : relax) {
    set_param(p, "hypre.relaxation", k, "test");
    EXPECT_EQ(hypre_options(p).at("relax_type"), v) << k;
  }
  set_param(p, "amg.strength_threshold", "0.5", "test");
  set_param(p, "hypre.aggressive_levels", "2", "test");
  set_param(p, "hypre.max_levels", "7", "test");
  EXPECT_EQ(hypre_options(p).at("strong_threshold"), 0.5);
  EXPECT_EQ(hypre_options(p).at("agg_num_levels"), 2);
  EXPECT_EQ(hypre_options(p).at("max_levels"), 7);
}

TEST(ExternalSolverParams, MueLuChoicesMapToParameterList) {
  Params p;
  set_param(p, "muelu.algorithm", "sa", "test");
  set_param(p, "amg.strength_threshold", "0.125", "test");
  set_param(p, "muelu.smoother", "sgs", "test");
  set_param(p, "muelu.smoother_sweeps", "3", "test");
  set_param(p, "muelu.coarse_size", "77", "test");
  set_param(p, "amg.max_levels", "6", "test");
  const std::string t = muelu_parameter_text(p);
  auto has = [&](const std::string& s) { return t.find(s) != std::string::npos; };
  EXPECT_TRUE(has("multigrid algorithm = sa")) << t;
  EXPECT_TRUE(has("aggregation: drop tol = 0.125")) << t;
  EXPECT_TRUE(has("smoother: type = RELAXATION")) << t;
  EXPECT_TRUE(has("relaxation: type = Symmetric Gauss-Seidel")) << t;
  EXPECT_TRUE(has("relaxation: sweeps = 3")) << t;
  EXPECT_TRUE(has("coarse: max size = 77")) << t;
  EXPECT_TRUE(has("max levels = 6")) << t;
  EXPECT_TRUE(has("reuse: type = tP")) << t;
  set_param(p, "muelu.smoother", "chebyshev", "test");
  set_param(p, "muelu.algorithm", "unsmoothed", "test");
  const std::string c = muelu_parameter_text(p);
  EXPECT_NE(c.find("smoother: type = CHEBYSHEV"), std::string::npos) << c;
  EXPECT_NE(c.find("chebyshev: degree = 3"), std::string::npos) << c;
  EXPECT_NE(c.find("multigrid algorithm = unsmoothed"), std::string::npos) << c;
}

// On K, Trilinos 13.2's RP reuse throws: the first reuse is refused with a message naming the key
// (a one-off solve, which builds, is not); the default (tP) runs the same scene to its end.
TEST(ExternalSolverParams, MueLuRpReuseRefusedOnPrimalForm) {
  Params p = resolve_params("bar_hang", {"resolution=2", "form=primal", "max_iterations=5", "muelu.reuse=RP"});
  const Problem prob = build_problem(p);
  const RunResult refused = run_simulation(prob, p, "muelu");
  EXPECT_TRUE(refused.status == "error" && refused.outer_iterations == 1) << refused.status;  // built, then refused
  EXPECT_NE(refused.message.find("muelu.reuse = RP"), std::string::npos) << refused.message;
  set_param(p, "muelu.reuse", "tP", "test");
  const RunResult ok = run_simulation(prob, p, "muelu");
  EXPECT_TRUE(ok.status != "error" && ok.outer_iterations == 5) << ok.status << ": " << ok.message;
}

// The strength threshold really reaches BoomerAMG: a stricter threshold keeps fewer strong
// connections, so the hierarchy changes (and both still solve).
TEST(ExternalSolverParams, StrengthThresholdChangesBoomerAmgHierarchy) {
  auto sys = make_system("bar_hang", 4, 3);
  std::vector<double> complexity;
  for (double theta : {0.1, 0.9}) {
    Params p = solver_params();
    p.amg.strength_threshold = theta;
    auto solver = make_linear_solver("hypre", p);
    solver->setup(sys->ds->A(), SetupKind::Structure, SetupContext{});
    check_solve(*solver, sys->ds->A(), sys->b, p.linear.tol, "hypre theta " + std::to_string(theta));
    complexity.push_back(solver->statistics().at("operator_complexity"));
  }
  EXPECT_NE(complexity[0], complexity[1]);
}

TEST(ExternalSolverParams, RegistryListsBothAsDistributed) {
  for (const char* n : {"hypre", "muelu"}) {
    const MethodInfo* m = find_method(n);
    ASSERT_NE(m, nullptr) << n;
    EXPECT_TRUE(m->available) << n << ": " << m->reason;
    EXPECT_TRUE(method_is_distributed(n));
  }
  EXPECT_FALSE(method_is_distributed("cholmod"));
  EXPECT_FALSE(method_is_distributed("mgpbd"));
}

// ---- MPI through the CLI -------------------------------------------------------------------
namespace {
const std::string bench = std::string(XB_BINARY_DIR) + "/xpbd-bench";
using test::clean_env;
using test::mpirun;

fs::path scratch() {
  const fs::path d = fs::temp_directory_path() / ("xb_ext_" + std::to_string(::getpid()));
  fs::create_directories(d);
  return d;
}

int sh(const std::string& cmd, std::string* err = nullptr) {
  const std::string e = (scratch() / "err.txt").string();
  const int st = std::system((clean_env() + cmd + " >" + (scratch() / "out.txt").string() + " 2>" + e).c_str());
  if (err) {
    std::ifstream f(e);
    std::stringstream s;
    s << f.rdbuf();
    *err = s.str();
  }
  return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

long long attr_int(const RunRecord& r, const std::string& k) { return std::get<long long>(r.attrs.at(k)); }

// Runs `xpbd-bench ARGS FILE` with one process (into one) and under mpirun with two ranks (into
// two); returns both files' runs, each expected to hold hypre's and muelu's.
std::pair<std::vector<RunRecord>, std::vector<RunRecord>> one_and_two_ranks(const std::string& args,
                                                                            const std::string& one,
                                                                            const std::string& two) {
  fs::remove(one);
  fs::remove(two);
  std::string err;
  EXPECT_EQ(sh(bench + args + one, &err), 0) << err;
  EXPECT_EQ(sh(mpirun + bench + args + two, &err), 0) << err;
  auto r1 = read_runs(one, false), r2 = read_runs(two, false);
  EXPECT_EQ(r1.size(), 2u);
  EXPECT_EQ(r2.size(), 2u);
  return {r1, r2};
}
}  // namespace

// The same small simulation with one process and with two: both ok, outer iterations within ±2,
// and the results say how many ranks ran.
TEST(ExternalSolverMpi, TwoRanksMatchOneProcess) {
  const std::string args =
      " run --scene bar_hang --solver hypre,muelu --set resolution=2 --set aspect=2 --set form=dual --set linear.forcing=fixed --out ";
  const std::string two = (scratch() / "np2.h5").string();
  const auto [r1, r2] = one_and_two_ranks(args, (scratch() / "np1.h5").string(), two);
  ASSERT_EQ(r1.size(), 2u);
  ASSERT_EQ(r2.size(), 2u);
  std::string err;
  for (size_t i = 0; i < 2; ++i) {
    EXPECT_EQ(std::get<std::string>(r2[i].attrs.at("status")), "ok") << r2[i].name;
    EXPECT_EQ(std::get<std::string>(r1[i].attrs.at("status")), "ok") << r1[i].name;
    EXPECT_NEAR(attr_int(r2[i], "outer_iterations"), attr_int(r1[i], "outer_iterations"), 2) << r2[i].name;
    EXPECT_EQ(std::get<double>(r2[i].attrs.at("mpi_ranks")), 2.0) << r2[i].name;
    EXPECT_EQ(std::get<double>(r1[i].attrs.at("mpi_ranks")), 1.0) << r1[i].name;
  }
  // report --format json carries the same fields for the MPI run.
  ASSERT_EQ(sh(bench + " report " + two + " --format json", &err), 0) << err;
  std::ifstream f(scratch() / "out.txt");
  std::stringstream s;
  s << f.rdbuf();
  EXPECT_NE(s.str().find("\"outer_iterations\""), std::string::npos);
  EXPECT_NE(s.str().find("\"operator_complexity\""), std::string::npos);
}

// A solver that cannot run distributed is refused with one line and a non-zero exit.
TEST(ExternalSolverMpi, NonDistributedSolverRefusedUnderMpi) {
  std::string err;
  const int rc = sh(mpirun + bench + " run --scene bar_hang --solver cholmod --set resolution=2 --out " +
                        (scratch() / "refused.h5").string(),
                    &err);
  EXPECT_NE(rc, 0);
  EXPECT_NE(err.find("cannot run distributed"), std::string::npos) << err;
  EXPECT_FALSE(fs::exists(scratch() / "refused.h5"));
}

// Captures `scene` at frame 0, iteration 1 and solves it with hypre and muelu, once with one
// process and once with two ranks: both ok at 1e-8 (recomputed by the harness), close to the
// direct solution, and iteration counts within ±2 of the one-process run.
namespace {
void expect_two_ranks_match_one_process(const std::string& scene, int resolution) {
  const std::string prefix = (scratch() / (scene + std::to_string(resolution))).string();
  std::string err;
  ASSERT_EQ(sh(bench + " capture --scene " + scene + " --set resolution=" + std::to_string(resolution) +
                   " --frame 0 --iteration 1 --out " + prefix,
               &err),
            0)
      << err;
  const auto [r1, r2] =
      one_and_two_ranks(" solve --system " + prefix + ".h5 --solver hypre,muelu --set form=dual --out ", prefix + "_np1.h5", prefix + "_np2.h5");
  ASSERT_EQ(r1.size(), 2u);
  ASSERT_EQ(r2.size(), 2u);
  for (size_t i = 0; i < 2; ++i) {
    EXPECT_EQ(std::get<std::string>(r2[i].attrs.at("status")), "ok") << r2[i].name;
    EXPECT_EQ(std::get<double>(r2[i].attrs.at("mpi_ranks")), 2.0) << r2[i].name;
    EXPECT_NEAR(attr_int(r2[i], "iterations"), attr_int(r1[i], "iterations"), 2) << r2[i].name;
    EXPECT_LE(std::get<double>(r2[i].attrs.at("final_relative_residual")), 1e-8 * 1.05) << r2[i].name;
    EXPECT_LE(std::get<double>(r2[i].attrs.at("error_vs_direct")), 1e-6) << r2[i].name;
  }
}
}  // namespace

// bar_hang, resolution 8: 12,288 rows. (Coarsening depends on the partition; on the 648-row
// resolution-3 bar the counts differed by 3 and 4 out of ~200-280.)
TEST(ExternalSolverMpi, SolveCapturedSystemTwoRanksMatchesOneProcess) { expect_two_ranks_match_one_process("bar_hang", 8); }

// cloth_hang, resolution 64: 12,416 rows. Two regressions behind it: with a column map sorted by
// global index MueLu's aggregation on rank 1 used wrong local indices and the job aborted ("fine
// level NS part has a zero column"); and with the cloth's edges numbered by type, a contiguous row
// block was one edge type, not a band of the cloth, and MueLu's rank-local aggregation needed 18%
// more iterations on 2 ranks (cloth 32²: 375 vs 303).
TEST(ExternalSolverMpi, SolveCapturedClothTwoRanksMatchesOneProcess) {
  expect_two_ranks_match_one_process("cloth_hang", 64);
}

// A system with a NaN in the matrix, solved by hypre and muelu with one process and under mpirun
// with two ranks: each library's run is recorded with status `error` and the same message in both,
// no run is lost, the exit code is 0 and no .tmp is left (a worker rank used to call MPI_Abort).
TEST(ExternalSolverMpi, NanSystemRecordsErrorOnEveryRankCount) {
  const std::string prefix = (scratch() / "nan_sys").string();
  std::string err;
  ASSERT_EQ(sh(bench + " capture --scene bar_hang --set resolution=2 --frame 0 --iteration 1 --out " + prefix, &err), 0) << err;
  {  // the last stored value of A: a row of the last rank's block
    const hid_t f = H5Fopen((prefix + ".h5").c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
    ASSERT_GE(f, 0);
    const hid_t ds = H5Dopen2(f, "/A/data", H5P_DEFAULT);
    const hid_t space = H5Dget_space(ds);
    const hsize_t n = H5Sget_simple_extent_npoints(space), last = n - 1, one = 1;
    H5Sselect_hyperslab(space, H5S_SELECT_SET, &last, nullptr, &one, nullptr);
    const hid_t mem = H5Screate_simple(1, &one, nullptr);
    const double nan = std::nan("");
    EXPECT_GE(H5Dwrite(ds, H5T_NATIVE_DOUBLE, mem, space, H5P_DEFAULT, &nan), 0);
    H5Sclose(mem);
    H5Sclose(space);
    H5Dclose(ds);
    H5Fclose(f);
  }
  const auto [r1, r2] =
      one_and_two_ranks(" solve --system " + prefix + ".h5 --solver hypre,muelu --set form=dual --out ", prefix + "_np1.h5", prefix + "_np2.h5");
  ASSERT_EQ(r1.size(), 2u);
  ASSERT_EQ(r2.size(), 2u);
  for (size_t i = 0; i < 2; ++i) {
    EXPECT_EQ(std::get<std::string>(r2[i].attrs.at("status")), "error") << r2[i].name;
    EXPECT_EQ(std::get<std::string>(r1[i].attrs.at("status")), "error") << r1[i].name;
    const std::string m = std::get<std::string>(r2[i].attrs.at("message"));
    EXPECT_NE(m.find("non-finite"), std::string::npos) << m;
    EXPECT_EQ(m, std::get<std::string>(r1[i].attrs.at("message")));
  }
  EXPECT_FALSE(fs::exists(prefix + "_np2.h5.tmp"));
  EXPECT_FALSE(fs::exists(prefix + "_np1.h5.tmp"));
}

