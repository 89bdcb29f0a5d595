// Constructors of the linear solvers, used by the registry (solvers/registry.cpp).
#pragma once

#include "linear_solver.hpp"

namespace xb {
std::unique_ptr<LinearSolver> make_cg(const SolverSettings& p);
std::unique_ptr<LinearSolver> make_jacobi_pcg(const SolverSettings& p);
std::unique_ptr<LinearSolver> make_cholmod(const SolverSettings& p);
// The in-house MGPBD AMG-PCG (solvers/amg/mgpbd.cpp, solvers/amg/).
std::unique_ptr<LinearSolver> make_mgpbd(const SolverSettings& p);
// hypre and muelu run distributed under MPI (solvers/mpi/distributed.hpp).
std::unique_ptr<LinearSolver> make_hypre(const SolverSettings& p);
std::unique_ptr<LinearSolver> make_muelu(const SolverSettings& p);
}  // namespace xb
