// Trilinos: MueLu (aggregation AMG, one V-cycle) as the left preconditioner of Belos CG on a
// Tpetra matrix with this rank's rows. ALL Trilinos headers live in this translation unit (they
// take long to compile).
//
// Stopping test: Belos::StatusTestGenResNorm on the implicit (recurrence) residual, 2-norm,
// scaled by ‖b‖₂ (NormOfRHS): ‖r‖₂ ≤ tol·‖b‖₂; zero initial guess.
// Residual history: we drive Belos::CGIter ourselves (the CG solver managers accept no user
// status test) with a status test that wraps the residual test: every time CG asks "converged?"
// (once per iteration, k = 0 included) it records the implicit residual ‖r_k‖₂ the residual test
// just computed, with the time since the start of the solve.
// Lazy setup: MueLu's "reuse: type" (muelu.reuse). Structure setups, and Values setups once
// amg.setup_interval frames have passed since the last full setup, build a new hierarchy
// ("structure" / "values"); other Values setups call MueLu::ReuseTpetraPreconditioner, which for
// RP keeps P and R and recomputes the coarse operators RAP and the smoothers ("reuse-RP"), for
// tP keeps the tentative prolongator and redoes the rest ("reuse-tP"). muelu.reuse = none rebuilds
// on every setup.
#include "distributed.hpp"
#include "../setup_policy.hpp"
#include "../timer.hpp"

#include "../../core/error.hpp"
#include "../solver_settings.hpp"

#include <BelosCGIter.hpp>
#include <BelosLinearProblem.hpp>
#include <BelosOutputManager.hpp>
#include <BelosStatusTestCombo.hpp>
#include <BelosStatusTestGenResNorm.hpp>
#include <BelosStatusTestMaxIters.hpp>
#include <BelosTpetraAdapter.hpp>
#include <MueLu_CreateTpetraPreconditioner.hpp>
#include <MueLu_TpetraOperator.hpp>
#include <Teuchos_DefaultMpiComm.hpp>
#include <Tpetra_Core.hpp>
#include <Tpetra_CrsMatrix.hpp>
#include <Tpetra_MultiVector.hpp>

#include <algorithm>
#include <cmath>
#include <sstream>

namespace xb {

namespace {

using SC = double;
using Map = Tpetra::Map<>;
using LO = Map::local_ordinal_type;
using GO = Map::global_ordinal_type;
using NO = Map::node_type;
using CrsMatrix = Tpetra::CrsMatrix<SC, LO, GO, NO>;
using MV = Tpetra::MultiVector<SC, LO, GO, NO>;
using OP = Tpetra::Operator<SC, LO, GO, NO>;
using Prec = MueLu::TpetraOperator<SC, LO, GO, NO>;
using Teuchos::RCP;
using Teuchos::rcp;

bool g_tpetra_started = false;

// Aggregation drop tolerances on block systems (see make_parameters).
constexpr double kBlockDropTol = 0.05, kBlockCoarseDropTol = 0.01;

void ensure_tpetra() {
  if (Tpetra::isInitialized()) return;
  // MPI is already initialised by main(); Tpetra then only starts Kokkos.
  int argc = 0;
  char** argv = nullptr;
  Tpetra::initialize(&argc, &argv);
  g_tpetra_started = true;
}

// Teuchos exceptions span several lines (file, throw number, test); the last one says what.
std::string last_line(const std::string& text) {
  std::istringstream is(text);
  std::string line, last;
  while (std::getline(is, line))
    if (line.find_first_not_of(" \t\r") != std::string::npos) last = line;
  return last.empty() ? text : last;
}

// Records ‖r_k‖₂ = (relative residual of `conv`)·‖b‖₂ with a time stamp at every check.
class HistoryTest final : public Belos::StatusTest<SC, MV, OP> {
 public:
  HistoryTest(RCP<Belos::StatusTestGenResNorm<SC, MV, OP>> conv, double bnorm, const Timer* clock,
              std::vector<double>* norms, std::vector<double>* times)
      : conv_(conv), bnorm_(bnorm), clock_(clock), norms_(norms), times_(times) {}
  Belos::StatusType checkStatus(Belos::Iteration<SC, MV, OP>* it) override {
    status_ = conv_->checkStatus(it);
    const std::vector<double>* v = conv_->getTestValue();
    norms_->push_back(v && !v->empty() ? (*v)[0] * bnorm_ : std::nan(""));
    times_->push_back(clock_->seconds());
    return status_;
  }
  Belos::StatusType getStatus() const override { return status_; }
  void reset() override {
    conv_->reset();
    status_ = Belos::Undefined;
  }
  void print(std::ostream& os, int indent) const override { conv_->print(os, indent); }

 private:
  RCP<Belos::StatusTestGenResNorm<SC, MV, OP>> conv_;
  double bnorm_;
  const Timer* clock_;
  std::vector<double>*norms_, *times_;
  Belos::StatusType status_ = Belos::Undefined;
};

class MueLuKernel final : public DistributedKernel {
 public:
  explicit MueLuKernel(const SolverSettings& p) : p_(p), policy_(p.amg.setup_interval) {
    // Belos CG's status test reads the 2-norm of the recurrence residual only.
    if (p.linear.stop_norm == "energy")
      throw Error("muelu: linear.stop_norm = energy is not available (Belos CG stops on the 2-norm); use dual or primal");
    ensure_tpetra();
    comm_ = rcp(new Teuchos::MpiComm<int>(MPI_COMM_WORLD));
    make_parameters(p, 1);  // rejects bad choices now, on every rank
  }

  // The harness keys → MueLu parameter names (see README), for `block_size` unknowns per node.
  static Teuchos::ParameterList make_parameters(const SolverSettings& p, int block_size) {
    Teuchos::ParameterList L;
    L.set("verbosity", "none");
    L.set("problem: symmetric", true);
    // Nodes of block_size rows: aggregation on the amalgamated (node) graph, and with the rigid
    // modes as "Nullspace" (user data, set in setup) a tentative P per aggregate from its QR.
    L.set("number of equations", block_size);
    L.set("max levels", p.amg.max_levels);
    L.set("coarse: max size", p.muelu.coarse_size);
    L.set("coarse: type", "KLU2");
    const std::string& a = p.muelu.algorithm;
    if (a != "auto" && a != "sa" && a != "unsmoothed")
      throw Error("muelu.algorithm: unknown '" + a + "' (valid: auto, unsmoothed, sa)");
    L.set("multigrid algorithm", a != "auto" ? a : block_size > 1 ? "sa" : "unsmoothed");
    L.set("aggregation: type", "uncoupled");
    if (block_size == 1) {
      L.set("aggregation: drop tol", p.amg.strength_threshold);
    } else {
      // K (measured on cloth_hang and bar_hang): the dual's 0.25 cut cloth's couplings so that
      // CG needed 6-8x the iterations, and no dropping left bar_hang at 4x. 0.05 on the fine
      // level with 0.01 below gave the fewest iterations on both. A node whose couplings are all
      // dropped is kept as its own aggregate ("preserve Dirichlet points"); MueLu otherwise
      // leaves it out of every aggregate, and on the bar a whole coarse level was left out, so
      // the coarsest matrix was singular (KLU2: numeric factorization failed).
      L.set("aggregation: drop tol", kBlockDropTol);
      for (int l = 2; l < p.amg.max_levels; ++l)  // "level l" builds level l from level l − 1
        L.sublist("level " + std::to_string(l)).set("aggregation: drop tol", kBlockCoarseDropTol);
      L.set("aggregation: preserve Dirichlet points", true);
    }
    // Amesos2's KLU2 on a matrix spread over several ranks returned wrong solutions here
    // (Trilinos 13.2: ‖M⁻¹Av − v‖ ≈ 400‖v‖ for a one-level hierarchy on 2 ranks, and CG stalled at
    // 1000 iterations with two levels). Under MPI, a level with fewer than coarse-size rows per
    // rank is therefore moved onto one rank (MueLu repartitioning; one part needs no partitioner
    // input), so the direct coarse solve always runs on a single rank.
    if (mpi_size() > 1) {
      L.set("repartition: enable", true);
      L.set("repartition: partitioner", "zoltan2");
      L.set("repartition: start level", 0);
      L.set("repartition: min rows per proc", p.muelu.coarse_size);
      L.set("repartition: max imbalance", 1.2);
    } else {
      L.set("repartition: enable", false);
    }
    if (p.muelu.reuse != "none" && p.muelu.reuse != "tP" && p.muelu.reuse != "RP")
      throw Error("muelu.reuse: unknown '" + p.muelu.reuse + "' (valid: none, tP, RP)");
    L.set("reuse: type", p.muelu.reuse);
    set_smoother(L, p);
    return L;
  }

  static void set_smoother(Teuchos::ParameterList& L, const SolverSettings& p) {
    const std::string& s = p.muelu.smoother;
    if (s == "chebyshev") {
      L.set("smoother: type", "CHEBYSHEV");
      auto& sp = L.sublist("smoother: params");
      sp.set("chebyshev: degree", p.muelu.smoother_sweeps);
      // Ifpack2's default 10 power iterations can underestimate lambda_max(D^-1 A) on these
      // systems; Chebyshev then amplifies the top of the spectrum, the V-cycle is indefinite and
      // CG breaks down (seen on a 96-row bar on 2 ranks) - the same failure mgpbd had.
      sp.set("chebyshev: eigenvalue max iterations", 50);
    } else if (s == "jacobi" || s == "sgs") {
      L.set("smoother: type", "RELAXATION");
      auto& sp = L.sublist("smoother: params");
      sp.set("relaxation: type", s == "jacobi" ? "Jacobi" : "Symmetric Gauss-Seidel");
      sp.set("relaxation: sweeps", p.muelu.smoother_sweeps);
    } else if (s == "gs") {
      // Forward sweeps before, backward after: the V-cycle stays symmetric for CG.
      L.set("smoother: pre type", "RELAXATION");
      L.set("smoother: post type", "RELAXATION");
      auto& pre = L.sublist("smoother: pre params");
      pre.set("relaxation: type", "Gauss-Seidel");
      pre.set("relaxation: sweeps", p.muelu.smoother_sweeps);
      auto& post = L.sublist("smoother: post params");
      post.set("relaxation: type", "Gauss-Seidel");
      post.set("relaxation: sweeps", p.muelu.smoother_sweeps);
      post.set("relaxation: backward mode", true);
    } else {
      throw Error("muelu.smoother: unknown '" + s + "' (valid: chebyshev, jacobi, gs, sgs)");
    }
  }

  void setup(const RowBlock& blk, SetupKind kind, const SetupContext& ctx) override {
    const bool same_pattern = kind == SetupKind::Values && A_ && blk.n_global == n_global_ &&
                              blk.first == first_ && blk.rows() == static_cast<int>(A_->getNodeNumRows()) &&
                              blk.block_size == block_size_;
    if (same_pattern) refill_matrix(blk);
    else build_matrix(blk);
    const bool rebuild = p_.muelu.reuse == "none" ||
                         policy_.rebuild(same_pattern ? SetupKind::Values : SetupKind::Structure, ctx, !prec_.is_null());
    if (rebuild) {
      build_hierarchy(blk);
      policy_.rebuilt(ctx);
      record_setup(kind == SetupKind::Structure ? "structure" : "values", true);
    } else {
      // On K (3 rows per node) Trilinos 13.2's RP reuse throws (Tpetra: "Trying to insert a new
      // entry into a static graph" in the coarse operator's product), on cloth, bar and squash
      // alike: refused with a message naming the key. A setup that builds is unaffected.
      if (blk.block_size > 1 && p_.muelu.reuse == "RP")
        throw Error("muelu.reuse = RP does not work on the primal form's K in Trilinos 13.2 (its coarse-operator "
                    "reuse throws); use tP or none, or form = dual");
      MueLu::ReuseTpetraPreconditioner(A_, *prec_);
      record_setup("reuse-" + p_.muelu.reuse, false);
    }
    collect_statistics();
  }

  LinearStats solve(const std::vector<double>& b, std::vector<double>& x, double tol) override {
    LinearStats st;
    if (!A_ || !prec_) throw Error("muelu: solve() before setup()");
    Timer clock;
    const size_t nl = b.size();
    RCP<MV> B = rcp(new MV(map_, 1)), X = rcp(new MV(map_, 1));  // X = 0
    {
      auto bv = B->getDataNonConst(0);
      for (size_t i = 0; i < nl; ++i) bv[i] = b[i];
    }
    std::vector<double> nb(1);
    B->norm2(Teuchos::ArrayView<double>(nb));
    const double bnorm = nb[0];
    x.assign(nl, 0.0);
    if (bnorm == 0) {
      st.residual_history = {0.0};
      st.residual_time = {0.0};
      return st;
    }
    auto problem = rcp(new Belos::LinearProblem<SC, MV, OP>(A_, X, B));
    problem->setLeftPrec(prec_);
    problem->setProblem();
    auto conv = rcp(new Belos::StatusTestGenResNorm<SC, MV, OP>(tol));
    conv->defineResForm(Belos::StatusTestGenResNorm<SC, MV, OP>::Implicit, Belos::TwoNorm);
    conv->defineScaleForm(Belos::NormOfRHS, Belos::TwoNorm);
    auto history = rcp(new HistoryTest(conv, bnorm, &clock, &st.residual_history, &st.residual_time));
    auto maxit = rcp(new Belos::StatusTestMaxIters<SC, MV, OP>(p_.linear.max_iterations));
    auto combo = rcp(new Belos::StatusTestCombo<SC, MV, OP>(Belos::StatusTestCombo<SC, MV, OP>::OR, history, maxit));
    auto out = rcp(new Belos::OutputManager<SC>(Belos::Errors));
    Teuchos::ParameterList cgp;
    cgp.set("Assert Positive Definiteness", true);
    Belos::CGIter<SC, MV, OP> cg(problem, out, combo, conv, cgp);
    problem->setLSIndex(std::vector<int>{0});
    Belos::CGIterationState<SC, MV> state;
    state.R = Belos::MultiVecTraits<SC, MV>::CloneViewNonConst(
        *Teuchos::rcp_const_cast<MV>(problem->getInitResVec()), std::vector<int>{0});
    try {
      cg.initializeCG(state);
      cg.iterate();
      st.status = conv->getStatus() == Belos::Passed ? LinearStatus::converged : LinearStatus::max_iterations;
    } catch (const Belos::CGIterateFailure& e) {
      st.status = LinearStatus::breakdown;
      st.message = "Belos CG: " + last_line(e.what());
    }
    problem->setCurrLS();
    st.iterations = cg.getNumIters();
    auto xv = X->getData(0);
    for (size_t i = 0; i < nl; ++i) x[i] = xv[i];
    return st;
  }

 private:
  void refill_matrix(const RowBlock& blk) {
    A_->resumeFill();
    for (int i = 0; i < blk.rows(); ++i) {
      const int b = blk.rowptr[i], e = blk.rowptr[i + 1];
      A_->replaceGlobalValues(static_cast<GO>(blk.first + i), Teuchos::ArrayView<const GO>(&blk.cols[b], e - b),
                              Teuchos::ArrayView<const SC>(&blk.vals[b], e - b));
    }
    A_->fillComplete();
  }

  void build_matrix(const RowBlock& blk) {
    n_global_ = blk.n_global;
    first_ = blk.first;
    block_size_ = blk.block_size;
    map_ = rcp(new Map(static_cast<Tpetra::global_size_t>(blk.n_global), static_cast<size_t>(blk.rows()), 0, comm_));
    std::vector<size_t> per_row(blk.rows());
    for (int i = 0; i < blk.rows(); ++i) per_row[i] = blk.rowptr[i + 1] - blk.rowptr[i];
    // Tpetra builds the column map (own columns first, in row-map order): MueLu's uncoupled
    // aggregation assumes a row's local index is also its local column index. A column map
    // sorted by global index broke that on ranks > 0 (TentativePFactory: "fine level NS part
    // has a zero column" on a 49K-row cloth system, 2 ranks).
    A_ = rcp(new CrsMatrix(map_, Teuchos::ArrayView<const size_t>(per_row.data(), per_row.size())));
    for (int i = 0; i < blk.rows(); ++i) {
      const int b = blk.rowptr[i], e = blk.rowptr[i + 1];
      A_->insertGlobalValues(static_cast<GO>(blk.first + i), Teuchos::ArrayView<const GO>(&blk.cols[b], e - b),
                             Teuchos::ArrayView<const SC>(&blk.vals[b], e - b));
    }
    A_->fillComplete(map_, map_);
  }

  void build_hierarchy(const RowBlock& blk) {
    Teuchos::ParameterList L = make_parameters(p_, blk.block_size);
    auto& user = L.sublist("user data");
    if (blk.near_kernel.cols() > 0) {
      // The near-kernel basis (the rigid modes on K) replaces MueLu's default (one constant per
      // equation): aggregates' tentative P then interpolates rotations too.
      auto ns = rcp(new MV(map_, static_cast<size_t>(blk.near_kernel.cols())));
      for (int c = 0; c < blk.near_kernel.cols(); ++c) {
        auto col = ns->getDataNonConst(c);
        for (int i = 0; i < blk.rows(); ++i) col[i] = blk.near_kernel(i, c);
      }
      user.set("Nullspace", ns);
    }
    if (comm_->getSize() > 1) {
      // The partitioner wants coordinates, one per node: the global node index (1D) keeps parts
      // contiguous.
      const int bs = blk.block_size;
      auto node_map = rcp(new Map(static_cast<Tpetra::global_size_t>(blk.n_global / bs),
                                  static_cast<size_t>(blk.rows() / bs), 0, comm_));
      auto coords = rcp(new Tpetra::MultiVector<double, LO, GO, NO>(node_map, 1));
      auto c = coords->getDataNonConst(0);
      for (int i = 0; i < blk.rows() / bs; ++i) c[i] = static_cast<double>(blk.first / bs + i);
      c = Teuchos::null;
      user.set("Coordinates", coords);
      // A one-level hierarchy would leave the direct solve spread over the ranks: keep at
      // least two levels so the coarse one is moved onto a single rank.
      if (blk.n_global <= p_.muelu.coarse_size)
        L.set("coarse: max size", static_cast<int>(std::max<long long>(1, blk.n_global / 4)));
    }
    try {
      prec_ = MueLu::CreateTpetraPreconditioner(RCP<OP>(A_), L);
    } catch (const std::exception& e) {
      prec_ = Teuchos::null;
      throw Error("muelu setup: " + last_line(e.what()));
    }
  }

  void collect_statistics() {
    auto H = prec_->GetHierarchy();
    const int nl = H->GetNumLevels();
    std::vector<double> rows(nl, 0.0), nnz(nl, 0.0);
    for (int l = 0; l < nl; ++l) {
      auto level = H->GetLevel(l);
      // A rank left out of a repartitioned level has no matrix there (rank 0 always has one).
      if (!level->IsAvailable("A")) continue;
      RCP<Xpetra::Matrix<SC, LO, GO, NO>> Al;
      try {
        Al = level->Get<RCP<Xpetra::Matrix<SC, LO, GO, NO>>>("A");
      } catch (const std::exception&) {
        continue;  // stored as an Operator on a rank without rows there
      }
      if (Al.is_null()) continue;
      rows[l] = static_cast<double>(Al->getGlobalNumRows());
      nnz[l] = static_cast<double>(Al->getGlobalNumEntries());
    }
    record_levels(std::move(rows), std::move(nnz));
  }

  SolverSettings p_;
  RCP<const Teuchos::Comm<int>> comm_;
  RCP<const Map> map_;
  RCP<CrsMatrix> A_;
  RCP<Prec> prec_;
  long long n_global_ = -1, first_ = -1;
  int block_size_ = 1;
  SetupPolicy policy_;
};

}  // namespace

std::unique_ptr<DistributedKernel> make_muelu_kernel(const SolverSettings& p) { return std::make_unique<MueLuKernel>(p); }

// The MueLu parameter list a SolverSettings gives, as text (for tests and the README).
std::string muelu_parameter_text(const SolverSettings& p, int block_size) {
  std::ostringstream os;
  MueLuKernel::make_parameters(p, block_size).print(os);
  return os.str();
}

void finalize_muelu_runtime() {
  if (g_tpetra_started && Tpetra::isInitialized()) Tpetra::finalize();
  g_tpetra_started = false;
}

}  // namespace xb
