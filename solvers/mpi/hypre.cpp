// hypre: BoomerAMG (one V-cycle) as the preconditioner of hypre's ParCSR PCG, on the rows of
// this rank (contiguous blocks, see distributed.hpp).
//
// Stopping test: HYPRE_PCGSetTwoNorm(1) makes PCG stop on ‖r‖₂ ≤ tol·‖b‖₂; with
// linear.stop_norm = energy, TwoNorm(0): the C-norm √<C r, r> over √<C b, b> (C the V-cycle),
// PCG's natural norm. Absolute tolerance 0; zero initial guess; tol set per solve.
// Residual history: BoomerAMG is wrapped in our own preconditioner callback, which PCG calls with
// the current (recurrence) residual r_j of every iteration; the callback records ‖r_j‖₂ (one
// extra inner product per iteration) and the time since the start of the solve, then runs the
// V-cycle. The last entry is PCG's final recurrence norm (GetFinalRelativeResidualNorm·‖b‖₂)
// unless PCG already preconditioned that residual.
// Lazy setup: hypre 2.26 cannot refresh a BoomerAMG hierarchy for new values. hypre.reuse =
// none rebuilds it on every setup() ("structure"/"values" = full BoomerAMGSetup); hierarchy keeps
// the last hierarchy as the preconditioner of the new matrix (PCG and the finest-level smoother
// use the new A; coarse levels, interpolation and smoother weights are stale) until a Structure
// setup or amg.setup_interval frames have passed ("reuse-hierarchy").
// Block systems (the primal K, block_size 3): BoomerAMG's systems AMG with num_functions = 3
// (hypre's default dof map i mod 3 is our node-major order; row blocks split at multiples of 3).
// Measured on K of cloth_hang r64/r128 and bar_hang r8/r12 (the choice: docs/linear_methods.md):
//  - coarsening per function (SetNodal 0) needed the fewest iterations (cloth128: 19 per solve
//    against 21-23 for nodal norms 1, 2, 4, 6) and the lowest operator complexity on the bar
//    (1.14 against 1.74); nodal coarsening is therefore off (the "nodal" option, 0).
//  - rigid-mode interpolation vectors (SetInterpVectors with the 3 rotations) are not used: GM-2
//    raised cloth's operator complexity from 1.9 to 5.9 for the same iterations and its setup
//    failed on the bar (error 12, a bad argument inside hypre), GM-1 made PCG break down on
//    cloth, LN aborted in the setup; both need nodal coarsening, which costs iterations here.
#include "distributed.hpp"
#include "../setup_policy.hpp"
#include "../timer.hpp"

#include "../../core/error.hpp"
#include "../solver_settings.hpp"

#include <HYPRE.h>
#include <HYPRE_krylov.h>
#include <HYPRE_parcsr_ls.h>
#include <_hypre_parcsr_ls.h>

#include <cmath>
#include <mutex>

namespace xb {

namespace {

int coarsen_type(const std::string& s) {
  if (s == "Falgout") return 6;
  if (s == "PMIS") return 8;
  if (s == "HMIS") return 10;
  throw Error("hypre.coarsening: unknown '" + s + "' (valid: HMIS, PMIS, Falgout)");
}

int interp_type(const std::string& s) {
  if (s == "classical") return 0;
  if (s == "direct") return 3;
  if (s == "multipass") return 4;
  if (s == "ext+i") return 6;
  throw Error("hypre.interpolation: unknown '" + s + "' (valid: ext+i, classical, direct, multipass)");
}

// Every choice is symmetric (PCG needs a symmetric preconditioner).
int relax_type(const std::string& s) {
  if (s == "jacobi") return 0;      // weighted Jacobi (hypre's weight 1)
  if (s == "hgs") return 6;         // hybrid symmetric Gauss-Seidel
  if (s == "l1-gs") return 8;       // l1-scaled hybrid symmetric Gauss-Seidel
  if (s == "chebyshev") return 16;  // Chebyshev
  if (s == "l1-jacobi") return 18;  // l1-scaled Jacobi
  throw Error("hypre.relaxation: unknown '" + s + "' (valid: l1-jacobi, jacobi, hgs, l1-gs, chebyshev)");
}

void check(HYPRE_Int err, const char* what) {
  if (err && !(err & HYPRE_ERROR_CONV)) {
    HYPRE_ClearAllErrors();
    throw Error(std::string("hypre: ") + what + " failed (error " + std::to_string(err) + ")");
  }
}

// What our preconditioner callback needs: the BoomerAMG solver and where to log.
struct LoggedAmg {
  HYPRE_Solver amg = nullptr;
  Timer clock;
  std::vector<double> norms, times;
};

HYPRE_Int logged_amg_solve(HYPRE_Solver self, HYPRE_ParCSRMatrix A, HYPRE_ParVector r, HYPRE_ParVector z) {
  auto* L = reinterpret_cast<LoggedAmg*>(self);
  HYPRE_Real rr = 0;
  HYPRE_ParVectorInnerProd(r, r, &rr);
  L->norms.push_back(std::sqrt(rr));
  L->times.push_back(L->clock.seconds());
  return HYPRE_BoomerAMGSolve(L->amg, A, r, z);
}

// The hierarchy is built explicitly in setup(); PCG's setup must not rebuild it.
HYPRE_Int no_setup(HYPRE_Solver, HYPRE_ParCSRMatrix, HYPRE_ParVector, HYPRE_ParVector) { return 0; }

class HypreKernel final : public DistributedKernel {
 public:
  explicit HypreKernel(const SolverSettings& p) : p_(p), policy_(p.amg.setup_interval) {
    static std::once_flag once;
    std::call_once(once, [] { HYPRE_Init(); });
    // Validate the choices now (on every rank), not at the first setup.
    coarsen_type(p.hypre.coarsening);
    interp_type(p.hypre.interpolation);
    relax_type(p.hypre.relaxation);
    if (p.hypre.reuse != "none" && p.hypre.reuse != "hierarchy")
      throw Error("hypre.reuse: unknown '" + p.hypre.reuse + "' (valid: none, hierarchy)");
  }
  ~HypreKernel() override {
    destroy_pcg();
    destroy_amg();
    if (ij_amg_ == ij_) ij_amg_ = nullptr;
    destroy_matrix(ij_);
    destroy_matrix(ij_amg_);
    destroy_vectors();
  }

  void setup(const RowBlock& blk, SetupKind kind, const SetupContext& ctx) override {
    const HYPRE_BigInt lo = static_cast<HYPRE_BigInt>(blk.first);
    const HYPRE_BigInt hi = static_cast<HYPRE_BigInt>(blk.first + blk.rows() - 1);
    n_local_ = blk.rows();
    destroy_pcg();  // it refers to the previous matrix
    const bool rebuild = p_.hypre.reuse == "none" || policy_.rebuild(kind, ctx, amg_ != nullptr);
    // The matrix the hierarchy was built from stays alive while the hierarchy is in use.
    if (ij_ && ij_ != ij_amg_) destroy_matrix(ij_);
    ij_ = nullptr;
    HYPRE_IJMatrix ij;
    check(HYPRE_IJMatrixCreate(MPI_COMM_WORLD, lo, hi, lo, hi, &ij), "IJMatrixCreate");
    HYPRE_IJMatrixSetObjectType(ij, HYPRE_PARCSR);
    std::vector<HYPRE_Int> ncols(n_local_);
    std::vector<HYPRE_BigInt> rows(n_local_), cols(blk.cols.begin(), blk.cols.end());
    for (int i = 0; i < n_local_; ++i) {
      ncols[i] = blk.rowptr[i + 1] - blk.rowptr[i];
      rows[i] = lo + i;
    }
    if (n_local_) HYPRE_IJMatrixSetRowSizes(ij, ncols.data());
    check(HYPRE_IJMatrixInitialize(ij), "IJMatrixInitialize");
    if (n_local_)
      check(HYPRE_IJMatrixSetValues(ij, n_local_, ncols.data(), rows.data(), cols.data(), blk.vals.data()),
            "IJMatrixSetValues");
    check(HYPRE_IJMatrixAssemble(ij), "IJMatrixAssemble");
    ij_ = ij;
    void* obj = nullptr;
    HYPRE_IJMatrixGetObject(ij_, &obj);
    A_ = static_cast<HYPRE_ParCSRMatrix>(obj);

    if (!b_ || lo != lo_ || hi != hi_) {
      destroy_vectors();
      lo_ = lo;
      hi_ = hi;
      make_vector(b_ij_, b_);
      make_vector(x_ij_, x_);
    }

    if (rebuild) {
      destroy_amg();
      if (ij_amg_ && ij_amg_ != ij_) destroy_matrix(ij_amg_);
      ij_amg_ = ij_;
      build_amg(blk);
      policy_.rebuilt(ctx);
      record_setup(kind == SetupKind::Structure ? "structure" : "values", true);
    } else {
      record_setup("reuse-hierarchy", false);
    }
    // PCG is cheap to set up; a fresh one per matrix keeps its work vectors and matvec current.
    HYPRE_ParCSRPCGCreate(MPI_COMM_WORLD, &pcg_);
    HYPRE_PCGSetAbsoluteTol(pcg_, 0.0);
    HYPRE_PCGSetTwoNorm(pcg_, p_.linear.stop_norm == "energy" ? 0 : 1);
    HYPRE_PCGSetMaxIter(pcg_, p_.linear.max_iterations);
    HYPRE_PCGSetPrintLevel(pcg_, 0);
    HYPRE_PCGSetLogging(pcg_, 1);
    logged_.amg = amg_;
    HYPRE_ParCSRPCGSetPrecond(pcg_, logged_amg_solve, no_setup, reinterpret_cast<HYPRE_Solver>(&logged_));
    check(HYPRE_ParCSRPCGSetup(pcg_, A_, b_, x_), "PCGSetup");
  }

  LinearStats solve(const std::vector<double>& b, std::vector<double>& x, double tol) override {
    LinearStats st;
    if (!pcg_) throw Error("hypre: solve() before setup()");
    HYPRE_PCGSetTol(pcg_, tol);
    set_vector(b_ij_, b.data());
    std::vector<double> zero(n_local_, 0.0);
    set_vector(x_ij_, zero.data());
    double bb_local = 0;
    for (double v : b) bb_local += v * v;
    double bb = 0;
    MPI_Allreduce(&bb_local, &bb, 1, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD);
    const double bnorm = std::sqrt(bb);
    logged_.norms.clear();
    logged_.times.clear();
    logged_.clock.reset();
    x.assign(n_local_, 0.0);
    if (bnorm == 0) {
      st.residual_history = {0.0};
      st.residual_time = {0.0};
      return st;
    }
    const HYPRE_Int err = HYPRE_ParCSRPCGSolve(pcg_, A_, b_, x_);
    const double t_end = logged_.clock.seconds();
    HYPRE_ClearAllErrors();
    HYPRE_Int iters = 0;
    HYPRE_Real rel = 0;
    HYPRE_ParCSRPCGGetNumIterations(pcg_, &iters);
    HYPRE_ParCSRPCGGetFinalRelativeResidualNorm(pcg_, &rel);
    if (n_local_) {
      std::vector<HYPRE_BigInt> idx(n_local_);
      for (int i = 0; i < n_local_; ++i) idx[i] = lo_ + i;
      HYPRE_IJVectorGetValues(x_ij_, n_local_, idx.data(), x.data());
    }
    st.iterations = iters;
    st.residual_history = logged_.norms;
    st.residual_time = logged_.times;
    if (static_cast<int>(st.residual_history.size()) <= iters) {
      st.residual_history.push_back(rel * bnorm);
      st.residual_time.push_back(t_end);
    }
    if (!std::isfinite(rel)) {
      st.status = LinearStatus::breakdown;
      st.message = "hypre PCG: residual is not finite";
    } else if (rel <= tol) {
      st.status = LinearStatus::converged;
    } else if (iters >= p_.linear.max_iterations) {
      st.status = LinearStatus::max_iterations;
    } else {
      st.status = LinearStatus::breakdown;
      st.message = "hypre PCG stopped early (error " + std::to_string(err) + ") at relative residual " +
                   std::to_string(rel);
    }
    return st;
  }

 private:
  void build_amg(const RowBlock& blk) {
    HYPRE_BoomerAMGCreate(&amg_);
    HYPRE_BoomerAMGSetPrintLevel(amg_, 0);
    HYPRE_BoomerAMGSetMaxIter(amg_, 1);  // one V-cycle per application
    HYPRE_BoomerAMGSetTol(amg_, 0.0);
    // The options come from the one mapping table (hypre_options) that the tests check.
    const auto o = hypre_options(p_, blk.block_size);
    auto opt = [&](const char* k) { return static_cast<HYPRE_Int>(o.at(k)); };
    HYPRE_BoomerAMGSetCoarsenType(amg_, opt("coarsen_type"));
    HYPRE_BoomerAMGSetInterpType(amg_, opt("interp_type"));
    HYPRE_BoomerAMGSetRelaxType(amg_, opt("relax_type"));
    HYPRE_BoomerAMGSetCycleRelaxType(amg_, opt("coarsest_relax_type"), 3);  // Gaussian elimination
    HYPRE_BoomerAMGSetNumSweeps(amg_, opt("num_sweeps"));
    HYPRE_BoomerAMGSetStrongThreshold(amg_, o.at("strong_threshold"));
    HYPRE_BoomerAMGSetAggNumLevels(amg_, opt("agg_num_levels"));
    HYPRE_BoomerAMGSetMaxLevels(amg_, opt("max_levels"));
    if (opt("num_functions") > 1) {
      // Systems AMG: dof i belongs to function i mod block_size (hypre's default map, node-major).
      HYPRE_BoomerAMGSetNumFunctions(amg_, opt("num_functions"));
      HYPRE_BoomerAMGSetNodal(amg_, opt("nodal"));
    }
    check(HYPRE_BoomerAMGSetup(amg_, A_, b_, x_), "BoomerAMGSetup");
    record_hierarchy();
  }

  // Complexities (collective: every rank computes them, rank 0 reports).
  void record_hierarchy() {
    auto* data = reinterpret_cast<hypre_ParAMGData*>(amg_);
    const int nl = hypre_ParAMGDataNumLevels(data);
    hypre_ParCSRMatrix** As = hypre_ParAMGDataAArray(data);
    std::vector<double> rows(nl), nnz(nl);
    for (int l = 0; l < nl; ++l) {
      hypre_ParCSRMatrixSetNumNonzeros(As[l]);
      rows[l] = static_cast<double>(hypre_ParCSRMatrixGlobalNumRows(As[l]));
      nnz[l] = static_cast<double>(hypre_ParCSRMatrixNumNonzeros(As[l]));
    }
    record_levels(std::move(rows), std::move(nnz));
  }

  void make_vector(HYPRE_IJVector& ij, HYPRE_ParVector& v) {
    HYPRE_IJVectorCreate(MPI_COMM_WORLD, lo_, hi_, &ij);
    HYPRE_IJVectorSetObjectType(ij, HYPRE_PARCSR);
    HYPRE_IJVectorInitialize(ij);
    HYPRE_IJVectorAssemble(ij);
    void* obj = nullptr;
    HYPRE_IJVectorGetObject(ij, &obj);
    v = static_cast<HYPRE_ParVector>(obj);
  }
  void set_vector(HYPRE_IJVector ij, const double* vals) {
    if (!n_local_) return;
    std::vector<HYPRE_BigInt> idx(n_local_);
    for (int i = 0; i < n_local_; ++i) idx[i] = lo_ + i;
    HYPRE_IJVectorSetValues(ij, n_local_, idx.data(), vals);
  }
  void destroy_vectors() {
    if (b_ij_) HYPRE_IJVectorDestroy(b_ij_);
    if (x_ij_) HYPRE_IJVectorDestroy(x_ij_);
    b_ij_ = x_ij_ = nullptr;
    b_ = x_ = nullptr;
  }
  void destroy_pcg() {
    if (pcg_) HYPRE_ParCSRPCGDestroy(pcg_);
    pcg_ = nullptr;
  }
  void destroy_amg() {
    if (amg_) HYPRE_BoomerAMGDestroy(amg_);
    amg_ = nullptr;
  }
  static void destroy_matrix(HYPRE_IJMatrix& m) {
    if (m) HYPRE_IJMatrixDestroy(m);
    m = nullptr;
  }

  SolverSettings p_;
  int n_local_ = 0;
  HYPRE_BigInt lo_ = -1, hi_ = -1;
  HYPRE_IJMatrix ij_ = nullptr, ij_amg_ = nullptr;  // current matrix, matrix of the hierarchy
  HYPRE_ParCSRMatrix A_ = nullptr;
  HYPRE_IJVector b_ij_ = nullptr, x_ij_ = nullptr;
  HYPRE_ParVector b_ = nullptr, x_ = nullptr;
  HYPRE_Solver amg_ = nullptr, pcg_ = nullptr;
  LoggedAmg logged_;
  SetupPolicy policy_;
};

}  // namespace

std::map<std::string, double> hypre_options(const SolverSettings& p, int block_size) {
  return {{"coarsen_type", coarsen_type(p.hypre.coarsening)},
          {"interp_type", interp_type(p.hypre.interpolation)},
          {"relax_type", relax_type(p.hypre.relaxation)},
          {"coarsest_relax_type", 9},
          {"strong_threshold", p.amg.strength_threshold},
          {"agg_num_levels", p.hypre.aggressive_levels},
          {"max_levels", p.hypre.max_levels},
          {"num_sweeps", 1},
          {"pcg_two_norm", 1},
          {"num_functions", block_size},
          {"nodal", 0}};  // see the file comment
}

std::unique_ptr<DistributedKernel> make_hypre_kernel(const SolverSettings& p) { return std::make_unique<HypreKernel>(p); }

}  // namespace xb
