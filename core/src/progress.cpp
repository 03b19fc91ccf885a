#include "fullarm/core/progress.hpp"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>

namespace fullarm::core {
namespace {

constexpr int kBarWidth = 24;
constexpr double kBarRedrawS = 0.1;
constexpr std::size_t kLinesPerTask = 20;  // advance()'s lines in kLines mode, at most
constexpr double kMinLineIntervalS = 2.0;  // and no closer together than this

double steadySeconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

}  // namespace

ProgressMode progressModeFor(int fd, bool quiet) {
  if (quiet) return ProgressMode::kQuiet;
  const char* term = std::getenv("TERM");
  const bool dumb = term != nullptr && std::string_view(term) == "dumb";
  return ::isatty(fd) == 1 && !dumb ? ProgressMode::kBar : ProgressMode::kLines;
}

std::string formatDuration(double seconds) {
  const long total = std::isfinite(seconds) && seconds > 0.0 ? std::lround(seconds) : 0;
  char text[48];
  if (total < 60) {
    std::snprintf(text, sizeof text, "%ld s", total);
  } else if (total < 3600) {
    std::snprintf(text, sizeof text, "%ld min %02ld s", total / 60, total % 60);
  } else {
    std::snprintf(text, sizeof text, "%ld h %02ld min", total / 3600, (total % 3600) / 60);
  }
  return text;
}

Progress::Progress() = default;

Progress::Progress(std::ostream& out, ProgressMode mode, Clock clock)
    : out_(&out), mode_(mode), clock_(clock ? std::move(clock) : Clock(steadySeconds)) {}

Progress::~Progress() {
  const std::lock_guard lock(mutex_);
  closeBarLocked();
}

void Progress::begin(std::string name, std::size_t total_units) {
  if (mode_ == ProgressMode::kQuiet) return;
  const std::lock_guard lock(mutex_);
  closeBarLocked();
  open_ = true;
  name_ = std::move(name);
  total_ = total_units;
  done_ = 0;
  next_line_at_ = total_ > 0 ? (total_ + kLinesPerTask - 1) / kLinesPerTask : 1;
  start_s_ = clock_();
  last_draw_s_ = start_s_;
  last_what_.clear();
  showLocked({}, true);
}

void Progress::step(std::string_view what) {
  if (mode_ == ProgressMode::kQuiet) return;
  const std::lock_guard lock(mutex_);
  ++done_;
  showLocked(what, true);
}

void Progress::advance(std::size_t units) {
  if (mode_ == ProgressMode::kQuiet || units == 0) return;
  const std::lock_guard lock(mutex_);
  done_ += units;
  if (mode_ == ProgressMode::kLines) {
    const std::size_t every = total_ > 0 ? (total_ + kLinesPerTask - 1) / kLinesPerTask : 1;
    if (done_ < next_line_at_) return;
    next_line_at_ = (done_ / every + 1) * every;
    const double now_s = clock_();
    if (last_draw_s_ >= 0.0 && now_s - last_draw_s_ < kMinLineIntervalS) return;
    last_draw_s_ = now_s;
  }
  showLocked(last_what_, mode_ == ProgressMode::kLines);
}

void Progress::end(std::string_view summary) {
  if (mode_ == ProgressMode::kQuiet) return;
  const std::lock_guard lock(mutex_);
  if (!open_) return;
  closeBarLocked();
  *out_ << name_ << ": done in " << formatDuration(clock_() - start_s_);
  if (!summary.empty()) *out_ << ": " << summary;
  *out_ << "\n" << std::flush;
  open_ = false;
}

std::size_t Progress::done() const {
  const std::lock_guard lock(mutex_);
  return done_;
}

std::string Progress::statusLocked(std::string_view what) const {
  const double elapsed_s = clock_() - start_s_;
  std::string text = name_;
  if (total_ > 0) {
    text += " [" + std::to_string(done_) + "/" + std::to_string(total_) + "]";
  } else if (done_ > 0) {
    text += " [" + std::to_string(done_) + "]";
  }
  if (!what.empty()) {
    text += " ";
    text += what;
  }
  text += " (" + formatDuration(elapsed_s) + " elapsed";
  if (total_ > 0 && done_ > 0 && done_ < total_) {
    const double left_s = elapsed_s / static_cast<double>(done_) * static_cast<double>(total_ - done_);
    text += ", about " + formatDuration(left_s) + " left";
  }
  text += ")";
  return text;
}

void Progress::showLocked(std::string_view what, bool force) {
  if (!open_) return;
  if (!what.empty() && what.data() != last_what_.data()) last_what_ = std::string(what);
  if (mode_ == ProgressMode::kLines) {
    if (force) *out_ << statusLocked(what) << "\n" << std::flush;
    return;
  }
  // kBar: one line redrawn in place, at most every kBarRedrawS unless a named step finished.
  const double now_s = clock_();
  if (!force && last_draw_s_ >= 0.0 && now_s - last_draw_s_ < kBarRedrawS) return;
  last_draw_s_ = now_s;
  std::string bar(kBarWidth, '.');
  if (total_ > 0) {
    const auto filled = static_cast<std::size_t>(static_cast<double>(kBarWidth) *
                                                 static_cast<double>(std::min(done_, total_)) /
                                                 static_cast<double>(total_));
    std::fill_n(bar.begin(), filled, '#');
  }
  *out_ << "\r\x1b[K[" << bar << "] " << statusLocked(what) << std::flush;
  bar_drawn_ = true;
}

void Progress::closeBarLocked() {
  if (bar_drawn_ && out_ != nullptr) {
    *out_ << "\n" << std::flush;
  }
  bar_drawn_ = false;
}

Progress& progressOrQuiet(Progress* progress) {
  static Progress quiet;
  return progress != nullptr ? *progress : quiet;
}

}  // namespace fullarm::core
