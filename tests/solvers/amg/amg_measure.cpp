// xb_amg_measure: the measurements behind the AMG reports (docs/mgpbd.md), a tool, not a test.
//
//   xb_amg_measure systems [SYSTEMS] [VARIANTS]
//     For each system (a scene state built as the primal-form tests build theirs) it solves the
//     dual A Δλ = b with Jacobi-PCG and the primal K with Jacobi-PCG and with mgpbd's hierarchy in
//     each variant, all to dual relative residual 1e-8.
//     SYSTEMS  "scene/key=value/...;..."  (frames=N, iterations=N are the state, others Params keys)
//     VARIANTS "key=value,...;..." keys: theta smoother sweeps prol diag nk nkv extra ctheta nks max_coarse
//     XB_AMG_DUMP=DIR also writes K, f, the rigid modes, J, M⁻¹, α̃ and b as Matrix Market.
//   xb_amg_measure captured PREFIX.h5 [VARIANTS]
//     mgpbd's hierarchy level by level on the primal K of a captured system (amg_measure_captured.cpp).
//   xb_amg_measure scenes [small|default|big]
//     Levels, operator complexity, PCG iterations and times per smoother and near-kernel of the
//     dual mgpbd on cloth_hang and bar_hang after two outer iterations.
#include "solvers/amg/hierarchy.hpp"
#include "solvers/kernels.hpp"
#include "solvers/krylov/pcg.hpp"
#include "solvers/timer.hpp"
#include "amg_test_support.hpp"
#include "test_amg_primal.hpp"

#include <unsupported/Eigen/SparseExtra>

#include <cstdio>
#include <iostream>
#include <stdexcept>
#include <sstream>

using namespace xb;

namespace xb::test {
void measure_captured(const std::string& path, const std::vector<std::string>& variants);
}

namespace {
std::vector<std::string> split(const std::string& s, char sep) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  for (std::string item; std::getline(ss, item, sep);)
    if (!item.empty()) out.push_back(item);
  return out;
}

amg::AmgOptions variant_options(const std::string& spec) {
  amg::AmgOptions o = SolverSettings().amg;
  for (const std::string& kv : split(spec, ',')) {
    const size_t eq = kv.find('=');
    if (eq == std::string::npos) continue;  // "default"
    const std::string k = kv.substr(0, eq), v = kv.substr(eq + 1);
    if (k == "theta") o.nodal_strength_threshold = std::stod(v);
    else if (k == "smoother") o.smoother.kind = v;
    else if (k == "sweeps") o.smoother.sweeps = std::stoi(v);
    else if (k == "prol") o.prolongator = v;
    else if (k == "diag") o.prolongator_diagonal = v;
    else if (k == "nk") o.near_kernel.kind = v;
    else if (k == "nkv") o.near_kernel.vectors = std::stoi(v);
    else if (k == "extra") o.near_kernel.extra = std::stoi(v);
    else if (k == "ctheta") o.coarse_nodal_strength_threshold = std::stod(v);
    else if (k == "nks") o.near_kernel.sweeps = std::stoi(v);
    else if (k == "max_coarse") o.max_coarse = std::stoi(v);
    else throw std::invalid_argument("unknown variant key  + k + ");
  }
  return o;
}

void measure_variant(const test::PrimalCase& c, const std::string& spec) {
  const amg::AmgOptions o = variant_options(spec);
  amg::Hierarchy h;
  Timer ts;
  h.setup(c.K, o, {3, &c.rigid});
  const double setup = ts.seconds();
  Timer tr;
  h.refresh(c.K);
  const double refresh = tr.seconds();
  Vector x;
  Preconditioner M = [&](const Vector& r, Vector& z) { h.vcycle(r, z); };
  const LinearStats st = pcg(c.K, c.f, x, M, 1e-8, 5000, c.dual_measure());
  Vector r;
  residual(c.A(), c.recover(x), c.b, r);
  std::printf("  mgpbd K [%s]: %s levels %d oc %.2f gc %.2f its %d (dual rel %.1e) setup %.3f refresh %.3f solve %.3f s rows:",
              spec.c_str(), st.message.empty() ? to_string(st.status) : st.message.c_str(), h.num_levels(), h.operator_complexity(), h.grid_complexity(), st.iterations,
              r.norm() / c.b.norm(), setup, refresh, st.solve_time);
  for (double v : h.level_rows()) std::printf(" %g", v);
  std::printf("\n");
  std::fflush(stdout);
}

void measure_system(const std::string& spec, const std::vector<std::string>& variants) {
  const std::vector<std::string> parts = split(spec, '/');
  std::vector<std::pair<std::string, std::string>> overrides;
  int frames = 0, iterations = 0;
  for (size_t i = 1; i < parts.size(); ++i) {
    const size_t eq = parts[i].find('=');
    const std::string k = parts[i].substr(0, eq), v = parts[i].substr(eq + 1);
    if (k == "frames") frames = std::stoi(v);
    else if (k == "iterations") iterations = std::stoi(v);
    else overrides.emplace_back(k, v);
  }
  Timer tb;
  const test::PrimalCase c = test::primal_case(parts[0], overrides, frames, iterations);
  std::printf("%s: dual rows %ld nnz %ld, K rows %ld nnz %ld (built in %.1f s)\n", spec.c_str(), (long)c.A().rows(),
              (long)c.A().nonZeros(), (long)c.K.rows(), (long)c.K.nonZeros(), tb.seconds());
  Params p;
  p.linear.tol = 1e-8;
  p.linear.max_iterations = 100000;
  Vector x;
  auto jac = make_linear_solver("jacobi-pcg", p);
  jac->setup(c.A(), SetupKind::Structure, {});
  const LinearStats ds = jac->solve(c.b, x);
  std::printf("  jacobi-pcg A: its %d solve %.3f s\n", ds.iterations, ds.solve_time);
  jac = make_linear_solver("jacobi-pcg", p);
  jac->set_relative_residual(c.dual_measure());
  jac->setup(c.K, SetupKind::Structure, {});
  const LinearStats ks = jac->solve(c.f, x);
  std::printf("  jacobi-pcg K: its %d solve %.3f s\n", ks.iterations, ks.solve_time);
  std::fflush(stdout);
  if (const char* dir = std::getenv("XB_AMG_DUMP")) {
    // For outside tools (scripts, pyamg): K, f, the rigid modes, J, M⁻¹, α̃, b.
    const std::string pre = std::string(dir) + "/" + parts[0];
    Eigen::saveMarket(c.K, pre + "_K.mtx");
    Eigen::saveMarket(c.J, pre + "_J.mtx");
    Eigen::saveMarketVector(c.f, pre + "_f.mtx");
    Eigen::saveMarketVector(c.b, pre + "_b.mtx");
    Eigen::saveMarketVector(c.minv, pre + "_minv.mtx");
    Eigen::saveMarketVector(c.alpha_tilde, pre + "_at.mtx");
    Eigen::saveMarket(Eigen::SparseMatrix<double>(c.rigid.sparseView()), pre + "_B.mtx");
  }
  for (const std::string& v : variants) measure_variant(c, v);
}

void measure_systems(const std::string& systems, const std::string& variants) {
  for (const std::string& s : split(systems, ';')) measure_system(s, split(variants, ';'));
}

void measure_scenes(const std::string& size) {
  using namespace xb::test;
  std::vector<std::pair<std::string, int>> cases = {{"cloth_hang", 64}, {"bar_hang", 8}};
  if (size == "small") cases = {{"cloth_hang", 32}, {"bar_hang", 4}};
  else if (size == "big") cases = {{"cloth_hang", 128}, {"bar_hang", 12}};
  else if (size != "default") throw std::invalid_argument("size must be small, default or big, not '" + size + "'");
  for (const auto& [sc, res] : cases) {
    SceneSystem s = scene_system(sc, res, 2);
    const SparseMatrix& A = s.ds->A();
    Params p;
    p.linear.tol = 1e-8;
    p.linear.max_iterations = 100000;
    Vector x, r;
    auto cg = make_linear_solver("cg", p);
    cg->setup(A, SetupKind::Structure, {});
    const LinearStats cs = cg->solve(s.b, x);
    printf("%s res %d rows %ld nnz %ld: cg %d its solve %.3f s\n", sc.c_str(), res, (long)A.rows(), (long)A.nonZeros(), cs.iterations, cs.solve_time);
    for (const std::string nkv : {"ones", "gs", "gs4"})
      for (const std::string sm : {"jacobi", "chebyshev", "gs"})
        for (int sw : {1, 2}) {
          const std::string nk = nkv == "ones" ? "ones" : "gs";
          p.amg.smoother.kind = sm;
          p.amg.near_kernel.kind = nk;
          p.amg.near_kernel.vectors = nkv == "gs4" ? 4 : 1;
          p.amg.smoother.sweeps = sw;
          auto mg = make_linear_solver("mgpbd", p);
          mg->setup(A, SetupKind::Structure, {});
          const LinearStats ms = mg->solve(s.b, x);
          mg->setup(A, SetupKind::Values, {0, 0, 1});
          const LinearStats ms2 = mg->solve(s.b, x);
          residual(A, x, s.b, r);
          const auto st = mg->statistics();
          printf("  %s/%s x%d: levels %g oc %.3f gc %.3f its %d (true rel %.1e) setup %.4f refresh %.4f solve %.4f s rows:", nkv.c_str(), sm.c_str(), sw,
                 st.at("levels"), st.at("operator_complexity"), st.at("grid_complexity"), ms.iterations, r.norm() / s.b.norm(),
                 ms.setup_time, ms2.setup_time, ms.solve_time);
          const auto arrays = mg->array_statistics();
          for (double v : arrays.at("level_rows")) printf(" %g", v);
          printf("\n");
        }
  }
}
}  // namespace

int main(int argc, char** argv) {
  const std::string mode = argc > 1 ? argv[1] : "";
  try {
    if (mode == "systems")
      measure_systems(argc > 2 ? argv[2] : "cloth_hang/resolution=64/frames=3;bar_hang/resolution=8/frames=1",
                      argc > 3 ? argv[3] : "default;theta=0;prol=tentative;diag=block");
    else if (mode == "captured" && argc > 2)
      test::measure_captured(argv[2], split(argc > 3 ? argv[3] : "default", ';'));
    else if (mode == "scenes")
      measure_scenes(argc > 2 ? argv[2] : "default");
    else
      throw std::invalid_argument("usage: xb_amg_measure systems [SYSTEMS] [VARIANTS] | captured PREFIX.h5 [VARIANTS] | scenes [small|default|big]");
  } catch (const std::exception& e) {
    std::cerr << "xb_amg_measure: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
