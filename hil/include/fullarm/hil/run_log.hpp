#pragma once
/// @file
/// Run logs: every run writes one LCM event log (readable by lcm-logplayer and lcm::LogFile),
/// and replay reads it back.
///
/// RunLogWriter runs on its own, non-real-time thread: every `drain_period` it empties the
/// SpscRings the tick fills, turns each record into its LCM message, encodes it and appends it
/// to the log with lcm::LogFile; every `flush_period` it flushes the file to the kernel, so a
/// crashed run loses at most the last flush period. The real-time side only ever pushes
/// fixed-size records into rings (SpscRing::tryPush, @rt); nothing here runs on the tick.
///
/// LcmLogReader iterates the raw events of any LCM log and tells a truncated log (the file ends
/// inside its last event: every complete event before it is read, and warning() names the byte
/// offset) from a corrupt one (a bad sync word, an impossible channel or data length, a
/// channel name that is not text, event numbers that go backwards: RunLogError naming the byte
/// offset). RunLogReader adds decoding by channel into the fullarm_lcm message types; a payload
/// that does not decode as its channel's type is a RunLogError naming the offset and channel.
///
/// The LCM log format (lcm/eventlog.c): each event is a 28-byte big-endian header (sync word
/// 0xEDA1DA01, int64 event number, int64 timestamp [us], int32 channel length, int32 data
/// length), the channel name (no NUL), then the payload. It has no checksum: a flipped bit
/// inside a payload value is found only if it breaks the decoding.

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <thread>
#include <variant>
#include <vector>

#include "fullarm/hil/lcm_layout.hpp"
#include "fullarm/hil/log_records.hpp"
#include "fullarm/hil/spsc_ring.hpp"
#include "fullarm_lcm/haptic_status_t.hpp"
#include "fullarm_lcm/joint_state_t.hpp"
#include "fullarm_lcm/minima_set_t.hpp"
#include "fullarm_lcm/run_header_t.hpp"
#include "fullarm_lcm/supervisor_event_t.hpp"
#include "fullarm_lcm/valve_command_t.hpp"

namespace lcm {
class LogFile;
}

namespace fullarm::hil {

/// A log that cannot be opened, written or read. For a corrupt log, what() reads
/// `<file>: corrupt LCM log at byte offset <offset> [(channel <name>)]: <what is wrong>`.
class RunLogError : public std::runtime_error {
 public:
  RunLogError(const std::string& what, std::int64_t offset = -1, std::string channel = {});
  /// Byte offset of the event at fault (its first header byte); -1 if not about an event.
  [[nodiscard]] std::int64_t offset() const noexcept { return offset_; }
  /// Channel of the event at fault; empty if unknown.
  [[nodiscard]] const std::string& channel() const noexcept { return channel_; }

 private:
  std::int64_t offset_;
  std::string channel_;
};

/// LCM's bounds: a channel name has 1..63 characters, a message at most 2^28 bytes.
inline constexpr int kMaxLcmChannelChars = 63;
inline constexpr std::int64_t kMaxLcmMessageBytes = std::int64_t{1} << 28;
/// Size of an event header in an LCM log.
inline constexpr int kLcmEventHeaderBytes = 28;

// --- writing ---------------------------------------------------------------------------------

/// Options of a RunLogWriter.
struct RunLogWriterOptions {
  std::filesystem::path file;                  ///< the log to create (an existing one is replaced)
  std::chrono::milliseconds drain_period{2};   ///< how often the thread empties the rings
  std::chrono::milliseconds flush_period{50};  ///< how often the file is flushed to the kernel
};

/// Counters of a RunLogWriter.
struct RunLogStats {
  std::uint64_t events_written = 0;
  std::uint64_t bytes_written = 0;  ///< headers, channels and payloads
  std::uint64_t flushes = 0;
  std::uint64_t records_dropped = 0;  ///< refused by full rings (sum of SpscRing::dropped())
  std::uint64_t encode_errors = 0;    ///< records that could not become a message (skipped)
  std::uint64_t write_errors = 0;     ///< events the file refused (disk full, I/O error)
};

/// Writes one LCM event log from any number of SpscRings, on its own thread (start/stop) or
/// driven by its owner (drainOnce: lockstep runs and tests). Not for the real-time thread.
class RunLogWriter {
 public:
  /// Creates the log file.
  /// @throws RunLogError naming the file if it cannot be created
  explicit RunLogWriter(RunLogWriterOptions options);
  /// stop(): drains what is left, flushes, closes.
  ~RunLogWriter();
  RunLogWriter(const RunLogWriter&) = delete;
  RunLogWriter& operator=(const RunLogWriter&) = delete;

  /// Drains `ring` into `channel`, each record as its LCM message (JointStateRecord ->
  /// joint_state_t, ..., MinimaSetRecord -> its minima_set_t fragments). The ring must outlive
  /// the writer's use of it (until stop()). Only before start().
  template <class Record>
  void addSource(SpscRing<Record>& ring, std::string channel);

  /// Same with an encoder of the caller's: `encode(record, *this)` writes the record's events
  /// with writeMessage() (it runs on the writer thread).
  template <class Record>
  void addSource(SpscRing<Record>& ring, std::function<void(const Record&, RunLogWriter&)> encode);

  /// Starts the writer thread. Only once.
  void start();
  /// Stops the thread (if running), drains every ring until empty, flushes. Idempotent; the
  /// destructor calls it. Does not throw: see stats() and error().
  void stop() noexcept;
  /// True while the thread runs.
  [[nodiscard]] bool running() const noexcept { return thread_.joinable(); }

  /// Empties every ring once, in the order the sources were added, and flushes if the flush
  /// period has passed. Returns the number of records taken. Only while the thread is not
  /// running (the rings have one consumer).
  std::size_t drainOnce();

  /// Encodes `message` (any lcm-gen type) and appends it as one event on `channel` with
  /// timestamp `utime_us`; for events that come from no ring, such as the run header. Safe
  /// from any non-real-time thread, also while the writer thread runs. A failure is counted in
  /// stats() (and error()), not thrown.
  template <class Message>
  void writeMessage(const std::string& channel, std::int64_t utime_us, const Message& message);

  /// Flushes the file to the kernel now.
  void flush();

  /// Counters so far (any thread).
  [[nodiscard]] RunLogStats stats() const;
  /// The first write or encode error, empty if none.
  [[nodiscard]] std::string error() const;
  /// The log's path.
  [[nodiscard]] const std::filesystem::path& file() const noexcept { return options_.file; }

 private:
  struct Source {
    virtual ~Source() = default;
    virtual std::size_t drain(RunLogWriter& writer) = 0;
    [[nodiscard]] virtual std::uint64_t dropped() const noexcept = 0;
  };
  template <class Record>
  struct RingSource;

  // The two below expect file_mutex_ held; noteError takes it.
  void writeEncoded(const std::string& channel, std::int64_t utime_us, const void* data, int size);
  void noteErrorLocked(const std::string& what, bool encode);
  void noteError(const std::string& what, bool encode);
  void run();
  std::size_t drainAll();
  void flushIfDue();

  RunLogWriterOptions options_;
  std::vector<std::unique_ptr<Source>> sources_;
  std::unique_ptr<lcm::LogFile> log_;
  std::vector<std::uint8_t> buffer_;  ///< encoding scratch (guarded by file_mutex_)
  mutable std::mutex file_mutex_;     ///< the file, the buffer, the counters, the error
  RunLogStats stats_;
  std::string error_;
  std::chrono::steady_clock::time_point last_flush_;
  std::thread thread_;
  std::mutex wake_mutex_;
  std::condition_variable wake_;
  bool stop_requested_ = false;
  bool stopped_ = false;
};

/// Writes one record as its LCM message(s) (the encoders addSource(ring, channel) uses).
void writeRecord(RunLogWriter& writer, const std::string& channel, const JointStateRecord& record);
void writeRecord(RunLogWriter& writer, const std::string& channel, const ValveCommandRecord& record);
void writeRecord(RunLogWriter& writer, const std::string& channel, const HapticStatusRecord& record);
void writeRecord(RunLogWriter& writer, const std::string& channel, const SupervisorEventRecord& record);
/// A set as its fragmentCount(num_minima) minima_set_t events, all with the record's seq and
/// utime (seq and fragment_index together name one fragment).
void writeRecord(RunLogWriter& writer, const std::string& channel, const MinimaSetRecord& record);

// --- reading ---------------------------------------------------------------------------------

/// One raw event of an LCM log.
struct LcmLogEvent {
  std::int64_t offset = 0;  ///< byte offset of its header in the file
  std::int64_t event_number = 0;
  std::int64_t utime_us = 0;  ///< the event's timestamp
  std::string channel;
  std::vector<std::uint8_t> data;
};

/// Reads the events of an LCM log one by one, checking the framing (see the file comment).
class LcmLogReader {
 public:
  /// @throws RunLogError naming the file if it cannot be opened
  explicit LcmLogReader(const std::filesystem::path& file);
  ~LcmLogReader();
  LcmLogReader(const LcmLogReader&) = delete;
  LcmLogReader& operator=(const LcmLogReader&) = delete;

  /// Reads the next complete event into `event`. Returns false at the end of the log: the end
  /// of the file, or a truncated last event (then truncated() is true and warning() says
  /// where).
  /// @throws RunLogError naming the file and the byte offset for a corrupt log
  bool next(LcmLogEvent& event);

  /// True once next() met an incomplete last event.
  [[nodiscard]] bool truncated() const noexcept { return truncated_offset_ >= 0; }
  /// Byte offset of the incomplete last event; -1 if none.
  [[nodiscard]] std::int64_t truncatedOffset() const noexcept { return truncated_offset_; }
  /// `<file>: truncated LCM log: the event at byte offset N is incomplete (...); read the K
  /// complete events before it`; empty if the log is not truncated.
  [[nodiscard]] const std::string& warning() const noexcept { return warning_; }
  /// Complete events read so far.
  [[nodiscard]] std::int64_t eventsRead() const noexcept { return events_read_; }
  [[nodiscard]] const std::filesystem::path& file() const noexcept { return file_; }

 private:
  [[noreturn]] void corrupt(std::int64_t offset, const std::string& channel, const std::string& what) const;
  void markTruncated(std::int64_t offset, const std::string& what);
  /// Offset of the first plausible header of event `event_number` + 1 at or after `from`; -1.
  std::int64_t findNextEventHeader(std::int64_t from, std::int64_t event_number);

  std::filesystem::path file_;
  std::FILE* f_ = nullptr;
  std::int64_t size_ = 0;
  std::int64_t offset_ = 0;
  std::int64_t events_read_ = 0;
  std::int64_t last_event_number_ = -1;
  std::int64_t truncated_offset_ = -1;
  bool done_ = false;
  std::string warning_;
};

/// A decoded run-log message.
using RunLogMessage =
    std::variant<fullarm_lcm::run_header_t, fullarm_lcm::joint_state_t, fullarm_lcm::valve_command_t,
                 fullarm_lcm::minima_set_t, fullarm_lcm::haptic_status_t, fullarm_lcm::supervisor_event_t>;

/// One event of a run log, decoded.
struct RunLogEntry {
  LcmLogEvent event;
  RunLogMessage message;
};

/// Decodes `event` as `Message`: the whole payload must decode (type hash, lengths) with no
/// byte left over.
/// @throws RunLogError naming the file, offset, channel and type if it does not
template <class Message>
[[nodiscard]] Message decodeEvent(const LcmLogEvent& event, const std::filesystem::path& file);

/// Options of a RunLogReader.
struct RunLogReaderOptions {
  /// Skip events on channels that are not a run log's (a log recorded with lcm-logger may hold
  /// others); false makes them an error, as in a log RunLogWriter wrote.
  bool skip_unknown_channels = false;
};

/// Reads a run log: LcmLogReader plus decoding by channel (channel::k*).
class RunLogReader {
 public:
  /// @throws RunLogError naming the file if it cannot be opened
  explicit RunLogReader(const std::filesystem::path& file, RunLogReaderOptions options = {});

  /// Reads and decodes the next event. False at the end (see LcmLogReader::next).
  /// @throws RunLogError for a corrupt log, a payload that does not decode as its channel's
  ///         type, or (unless skipped) an unknown channel, naming the offset and channel
  bool next(RunLogEntry& entry);

  [[nodiscard]] bool truncated() const noexcept { return raw_.truncated(); }
  [[nodiscard]] std::int64_t truncatedOffset() const noexcept { return raw_.truncatedOffset(); }
  [[nodiscard]] const std::string& warning() const noexcept { return raw_.warning(); }
  /// Events skipped on unknown channels.
  [[nodiscard]] std::int64_t skipped() const noexcept { return skipped_; }

 private:
  LcmLogReader raw_;
  RunLogReaderOptions options_;
  std::int64_t skipped_ = 0;
};

// --- templates -------------------------------------------------------------------------------

template <class Record>
struct RunLogWriter::RingSource final : RunLogWriter::Source {
  RingSource(SpscRing<Record>& r, std::function<void(const Record&, RunLogWriter&)> e)
      : ring(r), encode(std::move(e)) {}
  std::size_t drain(RunLogWriter& writer) override {
    return ring.consumeAll([&](const Record& record) {
      try {
        encode(record, writer);
      } catch (const std::exception& e) {
        writer.noteError(e.what(), true);  // the record is skipped; the ring moves on
      }
    });
  }
  [[nodiscard]] std::uint64_t dropped() const noexcept override { return ring.dropped(); }
  SpscRing<Record>& ring;
  std::function<void(const Record&, RunLogWriter&)> encode;
};

template <class Record>
void RunLogWriter::addSource(SpscRing<Record>& ring, std::string channel) {
  addSource<Record>(ring, [channel = std::move(channel)](const Record& record, RunLogWriter& writer) {
    writeRecord(writer, channel, record);
  });
}

template <class Record>
void RunLogWriter::addSource(SpscRing<Record>& ring, std::function<void(const Record&, RunLogWriter&)> encode) {
  if (running()) throw RunLogError(options_.file.string() + ": addSource after start()");
  sources_.push_back(std::make_unique<RingSource<Record>>(ring, std::move(encode)));
}

template <class Message>
void RunLogWriter::writeMessage(const std::string& channel, std::int64_t utime_us, const Message& message) {
  const int size = message.getEncodedSize();
  std::lock_guard lock(file_mutex_);
  if (buffer_.size() < static_cast<std::size_t>(size)) buffer_.resize(static_cast<std::size_t>(size));
  if (message.encode(buffer_.data(), 0, size) != size) {
    noteErrorLocked(channel + ": a " + std::string(Message::getTypeName()) + " message did not encode", true);
    return;
  }
  writeEncoded(channel, utime_us, buffer_.data(), size);
}

template <class Message>
Message decodeEvent(const LcmLogEvent& event, const std::filesystem::path& file) {
  Message message;
  int used = -1;
  // A string length the generated decoder would read past the payload with is refused first.
  if (stringLengthsInPayload(event.data, static_cast<const Message*>(nullptr))) {
    try {
      used = message.decode(event.data.data(), 0, static_cast<int>(event.data.size()));
    } catch (const std::exception&) {
      used = -1;  // an impossible array length in the payload (std::length_error, bad_alloc)
    }
  }
  if (used < 0 || used != static_cast<int>(event.data.size())) {
    throw RunLogError(file.string() + ": corrupt LCM log at byte offset " + std::to_string(event.offset) +
                          " (channel " + event.channel + "): the " + std::to_string(event.data.size()) +
                          "-byte payload does not decode as " + Message::getTypeName() +
                          (used < 0 ? "" : " (" + std::to_string(used) + " bytes used)"),
                      event.offset, event.channel);
  }
  return message;
}

}  // namespace fullarm::hil
