// Live progress of long commands (run, sweep, capture, solve): one status line on stderr,
// redrawn in place by a thread at most 4 times a second — what runs, the frame and outer
// iteration, the relative dual residual, the elapsed time and an ETA. Only when stderr is a
// terminal and the command was not given --quiet: logs and pipes get the plain lines as before.
// In-house: no C++ progress library is packaged for Debian 12, and the line is ~100 lines here.
#pragma once

#include "../sim/simulation.hpp"

#include "../../solvers/timer.hpp"

#include <condition_variable>
#include <mutex>
#include <string>
#include <thread>

namespace xb {

class Args;

// Whether a command shows progress: stderr is a terminal and no --quiet.
bool progress_wanted(const Args& args);

class ProgressLine {
 public:
  // `head` is what the line starts with (e.g. "run: squash with mgpbd ...", which the caller has
  // printed unless it erases the line at the end); the status goes after it. Off: every call
  // does nothing. The destructor stops as stop() does.
  ProgressLine(bool on, std::string head);
  ~ProgressLine();
  ProgressLine(const ProgressLine&) = delete;
  ProgressLine& operator=(const ProgressLine&) = delete;

  // The status after the head and the fraction of the work done (for the ETA; < 0: unknown).
  void set(std::string status, double fraction);
  // The ETA as a count-down from `remaining` s now (a sweep's: the mean run time × runs left),
  // instead of from the fraction.
  void set_remaining(double remaining);
  // A simulation's state (frame f/N, iteration, relative dual residual) as the status; `prefix`
  // before it (e.g. "run 2/4"), `outer` = (done before this run, total) for the ETA of a sweep.
  void set_iteration(const IterationProgress& s, const std::string& prefix = "");
  // Stops the redraws and leaves the line at its head (the caller completes it).
  void stop() { finish(true); }
  // Stops the redraws and erases the whole line (a head the caller never printed).
  void erase() { finish(false); }

 private:
  void finish(bool keep_head);
  void loop();
  void draw();

  bool on_;
  std::string head_, status_;
  double fraction_ = -1;
  double remaining_ = -1, remaining_at_ = 0;  // set_remaining's estimate and when it was given
  Timer clock_;
  std::mutex mutex_;
  std::condition_variable wake_;
  bool stopping_ = false;
  std::thread thread_;
};

// "0:07", "12:34", "1:02:03".
std::string clock_text(double seconds);

}  // namespace xb
