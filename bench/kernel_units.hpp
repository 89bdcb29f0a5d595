// xb_bench's kernel table (--xb_mode=units) and smoother table (--xb_mode=smoothers) on one
// captured system, both forms, every time measured in the same process as one SpMV with the
// system's own matrix (the "SpMV unit") and a STREAM-like triad (the bandwidth floor).
#pragma once

#include "../harness/io/system_io.hpp"
#include "harness/params.hpp"

#include <string>

namespace xb::bench {

// Fill of A and K, values-only refresh, setup, V-cycle (double and single storage) and one PCG
// iteration of mgpbd and jacobi-pcg, per form, in ms and in SpMV units; SpMV against its floor.
// Prints a Markdown table; writes JSON to json_path unless empty. budget_s: time per kernel.
// cpu_time: every time (the triad's too) is the process's CPU time instead of wall time.
void kernel_units(const CapturedSystem& cs, const Params& p, double budget_s, const std::string& json_path,
                  bool cpu_time);

// For each smoother (dual: jacobi, chebyshev, gs; primal: the same and their block forms), mgpbd
// setup + solve to p.linear.tol: iterations, time and time per decade of the relative residual
// (cpu_time: the process's CPU time instead of wall time).
void smoother_table(const CapturedSystem& cs, const Params& p, const std::string& label, bool cpu_time);

}  // namespace xb::bench
