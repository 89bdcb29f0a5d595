#include "factories.hpp"
#include "mpi/distributed.hpp"

#include "../core/error.hpp"

#include <map>
#include <mutex>

namespace xb {

const char* to_string(LinearStatus s) {
  switch (s) {
    case LinearStatus::converged: return "converged";
    case LinearStatus::max_iterations: return "max_iterations";
    default: return "breakdown";
  }
}

namespace {
struct Entry {
  MethodInfo info;
  std::unique_ptr<LinearSolver> (*make)(const SolverSettings&);
  // What every MPI rank runs, for the distributed methods (solvers/mpi/): the worker ranks ask
  // the registry for it by name.
  std::unique_ptr<DistributedKernel> (*kernel)(const SolverSettings&) = nullptr;
};

const std::vector<Entry>& entries() {
  static const std::vector<Entry> e = {
      {{"xpbd-jacobi", true, true, "", "one Jacobi sweep of Eq. 10 per outer iteration (relaxed by xpbd.jacobi_relaxation)"}, nullptr},
      {{"xpbd-gs", true, true, "", "one Gauss-Seidel sweep of Eq. 10 per outer iteration (graph-coloured, parallel)"}, nullptr},
      {{"xpbd-authors", true, true, "", "the authors' XPBD baseline: Jacobi sweep, full dlambda, x relaxed by xpbd.position_relaxation, C <= 1e-6 skipped"}, nullptr},
      {{"vbd", true, true, "", "Vertex Block Descent (Chen et al. 2024): per-vertex Newton on E, colour by colour; stops on |grad E|", false, true}, nullptr},
      {{"avbd", true, true, "", "Augmented VBD (Giles et al. 2025): VBD with ramped stiffness and multipliers (rigid constraints, contact)", false, true}, nullptr},
      {{"cholmod", false, true, "", "Goldenthal's direct solve: CHOLMOD supernodal Cholesky of the global system"}, make_cholmod},
      {{"cg", false, true, "", "conjugate gradients on the global system"}, make_cg},
      {{"jacobi-pcg", false, true, "", "Jacobi-preconditioned conjugate gradients on the global system"}, make_jacobi_pcg},
      {{"mgpbd", false, true, "", "MGPBD: CG preconditioned by one V-cycle of in-house unsmoothed-aggregation AMG, lazy setup"}, make_mgpbd},
#ifdef XB_WITH_HYPRE
      {{"hypre", false, true, "", "hypre BoomerAMG-preconditioned PCG (MPI: rows in contiguous blocks)", true}, make_hypre, make_hypre_kernel},
#else
      {{"hypre", false, false, "built without hypre (XB_WITH_HYPRE=OFF or hypre not found)", "hypre BoomerAMG-PCG", true}, nullptr},
#endif
#ifdef XB_WITH_MUELU
      {{"muelu", false, true, "", "Trilinos MueLu-preconditioned Belos CG on Tpetra (MPI: rows in contiguous blocks)", true}, make_muelu, make_muelu_kernel},
#else
      {{"muelu", false, false, "built without Trilinos MueLu (XB_WITH_MUELU=OFF or MueLu/Belos/Tpetra not found)", "Trilinos MueLu-CG", true}, nullptr},
#endif
  };
  return e;
}
// The registered methods (register_method), by name; a map keeps their MethodInfo in place.
struct Extra {
  MethodInfo info;
  SolverFactory make;
};
std::mutex extras_mutex;
std::map<std::string, Extra>& extras() {
  static std::map<std::string, Extra> m;
  return m;
}

}  // namespace

void register_method(const MethodInfo& info, SolverFactory make) {
  for (const auto& e : entries())
    if (e.info.name == info.name) throw Error("method '" + info.name + "' is built in; a registered method needs another name");
  std::lock_guard<std::mutex> lock(extras_mutex);
  if (!extras().emplace(info.name, Extra{info, std::move(make)}).second)
    throw Error("a method named '" + info.name + "' is already registered (two solvers with one name in a call?)");
}

void unregister_method(const std::string& name) {
  std::lock_guard<std::mutex> lock(extras_mutex);
  extras().erase(name);
}

const std::vector<MethodInfo>& methods() {
  static const std::vector<MethodInfo> m = [] {
    std::vector<MethodInfo> v;
    for (const auto& e : entries()) v.push_back(e.info);
    return v;
  }();
  return m;
}

const MethodInfo* find_method(const std::string& name) {
  for (const auto& m : methods())
    if (m.name == name) return &m;
  std::lock_guard<std::mutex> lock(extras_mutex);
  auto it = extras().find(name);
  return it == extras().end() ? nullptr : &it->second.info;
}

std::unique_ptr<LinearSolver> make_linear_solver(const std::string& name, const SolverSettings& p) {
  for (const auto& e : entries()) {
    if (e.info.name != name) continue;
    if (!e.info.available) throw Error("solver '" + name + "' is not available: " + e.info.reason);
    if (!e.make) throw Error("'" + name + "' is a local method, not a linear solver");
    return e.make(p);
  }
  SolverFactory extra;
  {
    std::lock_guard<std::mutex> lock(extras_mutex);
    if (auto it = extras().find(name); it != extras().end()) extra = it->second.make;
  }
  if (extra) return extra(p);  // outside the lock: a factory may take its time
  std::string valid;
  for (const auto& e : entries())
    if (e.make) valid += (valid.empty() ? "" : ", ") + e.info.name;
  throw Error("unknown linear solver '" + name + "' (valid: " + valid + ")");
}

bool method_is_distributed(const std::string& name) {
  const MethodInfo* m = find_method(name);
  return m && m->distributed;
}

std::unique_ptr<DistributedKernel> make_distributed_kernel(const std::string& name, const SolverSettings& p) {
  for (const auto& e : entries())
    if (e.info.name == name && e.kernel) return e.kernel(p);
  throw Error("solver '" + name + "' has no distributed kernel in this build");
}

}  // namespace xb
