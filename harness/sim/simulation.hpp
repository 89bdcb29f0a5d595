// A simulation run — the stepper, Algorithm 4 of the supplemental — with any method in the inner
// step (the loop: class Simulation in simulation_impl.hpp, simulation.cpp and simulation_step.cpp):
//   per substep: v += h·g; x̃ = x + h·v; x = x̃; λ = 0
//     repeat: C, ∇C at x → dual residual ‖C + α̃λ‖ (logged) → stop? → method step
//             (local sweep, or A Δλ = b with b = −(C + α̃λ) in the dual or the primal form
//             (Params::form), with XPBD's simplifications as switches (global_step.hpp);
//             λ += Δλ; x += ω M⁻¹∇CᵀΔλ, or Newton on E: step = newton, newton.hpp)
//             → collisions (if the scene has colliders)
//     v = (x − x_old)/h
// A failed run is a result (its status), never a crash.
#pragma once

#include "run_options.hpp"

#include <string>

namespace xb {

// Runs `method` (a name from methods()) on a copy of `prob`. Never throws for a numerical
// failure; throws xb::Error for a bad method name.
RunResult run_simulation(const Problem& prob, const Params& p, const std::string& method, const RunOptions& opt = {});

}  // namespace xb
