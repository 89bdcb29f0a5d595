#include "progress.hpp"

#include "args.hpp"

#include <sys/ioctl.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <algorithm>
#include <cstdio>

namespace xb {

namespace {
constexpr auto kRedraw = std::chrono::milliseconds(250);  // at most 4 lines a second

int terminal_width() {
  winsize w{};
  return ioctl(STDERR_FILENO, TIOCGWINSZ, &w) == 0 && w.ws_col > 0 ? w.ws_col : 80;
}
}  // namespace

bool progress_wanted(const Args& args) { return !args.has("--quiet") && isatty(STDERR_FILENO); }

std::string clock_text(double seconds) {
  const long s = std::lround(std::max(0.0, seconds));
  char b[32];
  if (s >= 3600)
    std::snprintf(b, sizeof b, "%ld:%02ld:%02ld", s / 3600, s / 60 % 60, s % 60);
  else
    std::snprintf(b, sizeof b, "%ld:%02ld", s / 60, s % 60);
  return b;
}

ProgressLine::ProgressLine(bool on, std::string head) : on_(on), head_(std::move(head)) {
  if (on_) thread_ = std::thread([this] { loop(); });
}

ProgressLine::~ProgressLine() { stop(); }

void ProgressLine::set(std::string status, double fraction) {
  if (!on_) return;
  std::lock_guard<std::mutex> lock(mutex_);
  status_ = std::move(status);
  fraction_ = fraction;
}

void ProgressLine::set_iteration(const IterationProgress& s, const std::string& prefix) {
  if (!on_) return;
  // Done: whole substeps, and this one's iterations against its cap (so the ETA is an upper bound).
  const double per_frame = s.substeps, total = per_frame * s.frames;
  const double done = (s.frame - s.first_frame) * per_frame + s.substep +
                      std::min(1.0, s.iteration / std::max(1.0, double(s.max_iterations)));
  char b[160];
  char sub[48] = "";
  if (s.substeps > 1) std::snprintf(sub, sizeof sub, " substep %d/%d,", s.substep + 1, s.substeps);
  std::snprintf(b, sizeof b, "%s%sframe %d/%d,%s iteration %d, rel. residual %.1e", prefix.c_str(), prefix.empty() ? "" : ", ",
                s.frame - s.first_frame + 1, s.frames, sub, s.iteration, s.relative_dual_residual);
  set(b, total > 0 ? done / total : -1);
}

void ProgressLine::set_remaining(double remaining) {
  if (!on_) return;
  std::lock_guard<std::mutex> lock(mutex_);
  remaining_ = remaining;
  remaining_at_ = clock_.seconds();
}

void ProgressLine::finish(bool keep_head) {
  if (!on_) return;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (stopping_) return;
    stopping_ = true;
  }
  wake_.notify_all();
  thread_.join();
  std::fprintf(stderr, "\r\033[K%s", keep_head ? head_.c_str() : "");  // the caller completes the head
  std::fflush(stderr);
}

void ProgressLine::loop() {
  std::unique_lock<std::mutex> lock(mutex_);
  while (!wake_.wait_for(lock, kRedraw, [this] { return stopping_; })) draw();
}

void ProgressLine::draw() {  // under mutex_
  const double t = clock_.seconds();
  std::string tail = status_ + (status_.empty() ? "" : " | ") + clock_text(t);
  if (remaining_ >= 0)
    tail += ", ETA " + clock_text(std::max(0.0, remaining_ - (t - remaining_at_)));
  else if (fraction_ > 0 && fraction_ <= 1)
    tail += ", ETA " + clock_text(t * (1 - fraction_) / fraction_);
  // One row (a wrapped line could not be redrawn): the head gives way first, the numbers last.
  const size_t width = static_cast<size_t>(terminal_width()) - 1;
  std::string head = head_;
  if (head.size() + 1 + tail.size() > width) head.resize(width > tail.size() + 1 ? width - tail.size() - 1 : 0);
  std::string line = head + (head.empty() ? "" : " ") + tail;
  if (line.size() > width) line.resize(width);
  std::fprintf(stderr, "\r\033[K%s", line.c_str());
  std::fflush(stderr);
}

}  // namespace xb
