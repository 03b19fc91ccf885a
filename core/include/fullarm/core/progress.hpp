#pragma once
/// @file
/// Progress of long work (tuning, validation, a demo), for the person waiting at the terminal:
/// each step with the elapsed time and an estimate of the time left. One facility that every long
/// command reports through, so that they all look alike and `--quiet` silences them all.
///
/// Where the output goes: a live bar redrawn in place on one line when the stream is a terminal,
/// plain lines when it is not (a log file or CI stays readable), nothing when quiet. The commands
/// write it to stderr, so stdout keeps only results. Thread-safe: the jobs of a pool may report
/// concurrently. Offline (locks, formats text, writes to a stream), not @rt.

#include <chrono>
#include <cstddef>
#include <functional>
#include <mutex>
#include <ostream>
#include <string>
#include <string_view>

namespace fullarm::core {

/// How a Progress shows itself.
enum class ProgressMode {
  kQuiet,  ///< nothing at all
  kLines,  ///< one line per step (and per twentieth of the unnamed units, 2 s apart at least), never redrawn
  kBar,    ///< one line redrawn in place (carriage return and erase-to-end), for a terminal
};

/// The mode for output on file descriptor `fd`: kQuiet when `quiet`, kBar when `fd` is a
/// terminal (and TERM is not "dumb"), kLines otherwise.
[[nodiscard]] ProgressMode progressModeFor(int fd, bool quiet);

/// "8 s", "2 min 05 s", "1 h 02 min": a duration for people (negative counts as 0).
[[nodiscard]] std::string formatDuration(double seconds);

/// Reports the progress of one task at a time: begin() names the task and its number of units,
/// step() and advance() count finished units, end() closes it with the total time. The time left
/// is the elapsed time per finished unit times the units left, shown once a unit has finished.
///
///     core::Progress progress(std::cerr, core::progressModeFor(2, quiet));
///     progress.begin("tune", 14);
///     progress.step("SFE: linear stage");     // "tune [1/14] SFE: linear stage (9 s elapsed, about 1 min 57 s left)"
///     ...
///     progress.end("7 of 7 verified");         // "tune: done in 2 min 01 s: 7 of 7 verified"
class Progress {
 public:
  /// Seconds since an arbitrary origin (a steady clock unless a test passes its own).
  using Clock = std::function<double()>;

  /// A Progress that shows nothing (kQuiet).
  Progress();
  /// Reports to `out` (kept by reference: it must outlive this) in `mode`; `clock` defaults to
  /// std::chrono::steady_clock.
  Progress(std::ostream& out, ProgressMode mode, Clock clock = {});
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;
  /// Closes an open bar line.
  ~Progress();

  /// Starts the task `name` of `total_units` units (0: unknown, no estimate); an open task is
  /// ended first.
  void begin(std::string name, std::size_t total_units);
  /// One unit finished, named `what`: a line in kLines mode, a redraw in kBar mode.
  void step(std::string_view what);
  /// `units` unnamed units finished (a Monte-Carlo's runs): in kLines mode a line each time the
  /// count passes another twentieth of the total, at most one every 2 s (the end line closes
  /// the task); in kBar mode a redraw at most every 0.1 s.
  void advance(std::size_t units = 1);
  /// Ends the task with a line of its total time and `summary` (may be empty).
  void end(std::string_view summary = {});

  [[nodiscard]] ProgressMode mode() const noexcept { return mode_; }
  /// Units finished in the current task.
  [[nodiscard]] std::size_t done() const;

 private:
  void showLocked(std::string_view what, bool force);
  [[nodiscard]] std::string statusLocked(std::string_view what) const;
  void closeBarLocked();

  std::ostream* out_ = nullptr;
  ProgressMode mode_ = ProgressMode::kQuiet;
  Clock clock_;
  mutable std::mutex mutex_;
  bool open_ = false;
  bool bar_drawn_ = false;
  std::string name_;
  std::size_t total_ = 0;
  std::size_t done_ = 0;
  std::size_t next_line_at_ = 0;  // kLines: the unit count of advance()'s next line
  double start_s_ = 0.0;
  double last_draw_s_ = -1.0;
  std::string last_what_;
};

/// `progress`, or a shared quiet Progress when it is null: lets a library function take an
/// optional `Progress*` and report unconditionally.
[[nodiscard]] Progress& progressOrQuiet(Progress* progress);

}  // namespace fullarm::core
