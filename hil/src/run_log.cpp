#include "fullarm/hil/run_log.hpp"

#include <lcm/lcm-cpp.hpp>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstring>

namespace fullarm::hil {
namespace {

constexpr std::array<std::uint8_t, 4> kSync = {0xED, 0xA1, 0xDA, 0x01};

std::uint64_t bigEndian(const std::uint8_t* p, int n) noexcept {
  std::uint64_t v = 0;
  for (int i = 0; i < n; ++i) v = (v << 8) | p[i];
  return v;
}

bool printable(std::uint8_t c) noexcept {
  return c >= 0x20 && c <= 0x7e;
}

std::string hexByte(std::uint8_t c) {
  static const char* digits = "0123456789abcdef";
  return std::string("0x") + digits[c >> 4] + digits[c & 0xf];
}

/// Reads exactly n bytes at offset (n may be 0); false on a short read.
bool readAt(std::FILE* f, std::int64_t offset, void* out, std::size_t n) {
  if (n == 0) return true;
  if (std::fseek(f, static_cast<long>(offset), SEEK_SET) != 0) return false;
  return std::fread(out, 1, n, f) == n;
}

}  // namespace

RunLogError::RunLogError(const std::string& what, std::int64_t offset, std::string channel)
    : std::runtime_error(what), offset_(offset), channel_(std::move(channel)) {}

// --- writer ----------------------------------------------------------------------------------

RunLogWriter::RunLogWriter(RunLogWriterOptions options) : options_(std::move(options)) {
  errno = 0;
  log_ = std::make_unique<lcm::LogFile>(options_.file.string(), "w");
  if (!log_->good()) {
    const int err = errno;
    throw RunLogError(options_.file.string() + ": cannot create the LCM log" +
                      (err != 0 ? std::string(" (") + std::strerror(err) + ")" : std::string()));
  }
  if (options_.drain_period.count() <= 0 || options_.flush_period.count() < 0) {
    throw RunLogError(options_.file.string() + ": drain_period must be > 0 ms and flush_period >= 0 ms (got " +
                      std::to_string(options_.drain_period.count()) + " ms, " +
                      std::to_string(options_.flush_period.count()) + " ms)");
  }
  last_flush_ = std::chrono::steady_clock::now();
}

RunLogWriter::~RunLogWriter() {
  stop();
}

void RunLogWriter::start() {
  if (running() || stopped_) throw RunLogError(options_.file.string() + ": the run log writer starts only once");
  thread_ = std::thread([this] { run(); });
}

void RunLogWriter::run() {
  std::unique_lock lock(wake_mutex_);
  while (!stop_requested_) {
    lock.unlock();
    drainAll();
    flushIfDue();
    lock.lock();
    wake_.wait_for(lock, options_.drain_period, [this] { return stop_requested_; });
  }
}

void RunLogWriter::stop() noexcept {
  try {
    if (thread_.joinable()) {
      {
        std::lock_guard lock(wake_mutex_);
        stop_requested_ = true;
      }
      wake_.notify_all();
      thread_.join();
    }
    if (!log_) return;
    // What the producers pushed before stopping is in the rings: take all of it.
    while (drainAll() > 0) {
    }
    flush();
    stopped_ = true;
  } catch (const std::exception& e) {
    noteError(std::string("stopping the writer: ") + e.what(), false);
  }
}

std::size_t RunLogWriter::drainOnce() {
  if (running()) throw RunLogError(options_.file.string() + ": drainOnce while the writer thread runs");
  const std::size_t n = drainAll();
  flushIfDue();
  return n;
}

std::size_t RunLogWriter::drainAll() {
  std::size_t n = 0;
  for (const auto& source : sources_) n += source->drain(*this);
  return n;
}

void RunLogWriter::flushIfDue() {
  if (std::chrono::steady_clock::now() - last_flush_ >= options_.flush_period) flush();
}

void RunLogWriter::flush() {
  std::lock_guard lock(file_mutex_);
  last_flush_ = std::chrono::steady_clock::now();
  if (std::fflush(log_->getFilePtr()) != 0) {
    noteErrorLocked(options_.file.string() + ": flush failed (" + std::strerror(errno) + ")", false);
    return;
  }
  ++stats_.flushes;
}

void RunLogWriter::writeEncoded(const std::string& channel, std::int64_t utime_us, const void* data, int size) {
  lcm::LogEvent event{};
  event.timestamp = utime_us;
  event.channel = channel;
  event.datalen = size;
  event.data = const_cast<void*>(data);  // lcm::LogFile takes a non-const pointer; it only reads
  if (log_->writeEvent(&event) != 0) {
    noteErrorLocked(
        options_.file.string() + ": writing an event on " + channel + " failed (" + std::strerror(errno) + ")", false);
    return;
  }
  ++stats_.events_written;
  stats_.bytes_written +=
      static_cast<std::uint64_t>(kLcmEventHeaderBytes) + channel.size() + static_cast<std::uint64_t>(size);
}

void RunLogWriter::noteErrorLocked(const std::string& what, bool encode) {
  ++(encode ? stats_.encode_errors : stats_.write_errors);
  if (error_.empty()) error_ = what;
}

void RunLogWriter::noteError(const std::string& what, bool encode) {
  std::lock_guard lock(file_mutex_);
  noteErrorLocked(what, encode);
}

RunLogStats RunLogWriter::stats() const {
  RunLogStats s;
  {
    std::lock_guard lock(file_mutex_);
    s = stats_;
  }
  s.records_dropped = 0;
  for (const auto& source : sources_) s.records_dropped += source->dropped();
  return s;
}

std::string RunLogWriter::error() const {
  std::lock_guard lock(file_mutex_);
  return error_;
}

void writeRecord(RunLogWriter& writer, const std::string& channel, const JointStateRecord& record) {
  writer.writeMessage(channel, record.utime_us, toMessage(record));
}
void writeRecord(RunLogWriter& writer, const std::string& channel, const ValveCommandRecord& record) {
  writer.writeMessage(channel, record.utime_us, toMessage(record));
}
void writeRecord(RunLogWriter& writer, const std::string& channel, const HapticStatusRecord& record) {
  writer.writeMessage(channel, record.utime_us, toMessage(record));
}
void writeRecord(RunLogWriter& writer, const std::string& channel, const SupervisorEventRecord& record) {
  writer.writeMessage(channel, record.utime_us, toMessage(record));
}
void writeRecord(RunLogWriter& writer, const std::string& channel, const MinimaSetRecord& record) {
  const int count = fragmentCount(record.num_minima);
  for (int i = 0; i < count; ++i) writer.writeMessage(channel, record.utime_us, toFragment(record, i, record.seq));
}

// --- raw reader ------------------------------------------------------------------------------

LcmLogReader::LcmLogReader(const std::filesystem::path& file) : file_(file) {
  f_ = std::fopen(file.string().c_str(), "rb");
  if (f_ == nullptr) {
    throw RunLogError(file.string() + ": cannot open the LCM log (" + std::strerror(errno) + ")");
  }
  if (std::fseek(f_, 0, SEEK_END) != 0 || (size_ = std::ftell(f_)) < 0) {
    std::fclose(f_);
    f_ = nullptr;
    throw RunLogError(file.string() + ": cannot read the LCM log's size");
  }
}

LcmLogReader::~LcmLogReader() {
  if (f_ != nullptr) std::fclose(f_);
}

void LcmLogReader::corrupt(std::int64_t offset, const std::string& channel, const std::string& what) const {
  throw RunLogError(file_.string() + ": corrupt LCM log at byte offset " + std::to_string(offset) +
                        (channel.empty() ? std::string() : " (channel " + channel + ")") + ": " + what,
                    offset, channel);
}

void LcmLogReader::markTruncated(std::int64_t offset, const std::string& what) {
  truncated_offset_ = offset;
  done_ = true;
  warning_ = file_.string() + ": truncated LCM log: the event at byte offset " + std::to_string(offset) +
             " is incomplete (" + what + "); read the " + std::to_string(events_read_) + " complete events before it";
}

bool LcmLogReader::next(LcmLogEvent& event) {
  if (done_) return false;
  const std::int64_t start = offset_;
  const std::int64_t remaining = size_ - start;
  if (remaining <= 0) {
    done_ = true;
    return false;
  }
  std::array<std::uint8_t, kLcmEventHeaderBytes> header{};
  const int have = static_cast<int>(std::min<std::int64_t>(remaining, kLcmEventHeaderBytes));
  if (!readAt(f_, start, header.data(), static_cast<std::size_t>(have))) corrupt(start, "", "read error");
  for (int i = 0; i < std::min(have, 4); ++i) {
    if (header[static_cast<std::size_t>(i)] != kSync[static_cast<std::size_t>(i)]) {
      std::string seen;
      for (int j = 0; j < std::min(have, 4); ++j) {
        if (j > 0) seen += ' ';
        seen += hexByte(header[static_cast<std::size_t>(j)]);
      }
      corrupt(start, "", "bad sync word " + seen + " (expected 0xed 0xa1 0xda 0x01)");
    }
  }
  if (have < kLcmEventHeaderBytes) {
    markTruncated(start, "the file ends after " + std::to_string(have) + " of its 28 header bytes");
    return false;
  }
  const auto event_number = static_cast<std::int64_t>(bigEndian(&header[4], 8));
  const auto timestamp = static_cast<std::int64_t>(bigEndian(&header[12], 8));
  const auto channel_len = static_cast<std::int32_t>(bigEndian(&header[20], 4));
  const auto data_len = static_cast<std::int32_t>(bigEndian(&header[24], 4));
  if (channel_len < 1 || channel_len > kMaxLcmChannelChars) {
    corrupt(start, "",
            "impossible channel length " + std::to_string(channel_len) + " (expected 1 .. " +
                std::to_string(kMaxLcmChannelChars) + ")");
  }
  if (data_len < 0 || data_len > kMaxLcmMessageBytes) {
    corrupt(start, "",
            "impossible data length " + std::to_string(data_len) + " (expected 0 .. " +
                std::to_string(kMaxLcmMessageBytes) + ")");
  }
  if (event_number < 0 || event_number <= last_event_number_) {
    corrupt(start, "",
            "event number " + std::to_string(event_number) + " after " + std::to_string(last_event_number_) +
                " (event numbers increase)");
  }
  const std::int64_t channel_at = start + kLcmEventHeaderBytes;
  const auto channel_have = static_cast<int>(std::min<std::int64_t>(channel_len, size_ - channel_at));
  std::string channel(static_cast<std::size_t>(channel_have), '\0');
  if (!readAt(f_, channel_at, channel.data(), channel.size())) corrupt(start, "", "read error");
  for (int i = 0; i < channel_have; ++i) {
    const auto c = static_cast<std::uint8_t>(channel[static_cast<std::size_t>(i)]);
    if (!printable(c)) {
      corrupt(
          start, "",
          "the channel name is not text (byte " + hexByte(c) + " at offset " + std::to_string(channel_at + i) + ")");
    }
  }
  if (channel_have < channel_len) {
    markTruncated(start, "the file ends inside its channel name, after " + std::to_string(channel_have) + " of " +
                             std::to_string(channel_len) + " characters");
    return false;
  }
  const std::int64_t data_at = channel_at + channel_len;
  const std::int64_t end = data_at + data_len;
  if (end > size_) {
    // The file ends inside this event's payload: a crash while writing it, unless a later event
    // begins inside what the length claims (then the length itself is wrong).
    const std::int64_t later = findNextEventHeader(data_at, event_number);
    if (later >= 0) {
      corrupt(start, channel,
              "data length " + std::to_string(data_len) +
                  " runs past the end of the file, but the next event begins at byte offset " + std::to_string(later));
    }
    markTruncated(start, "channel " + channel + ": the file ends after " + std::to_string(size_ - data_at) +
                             " of its " + std::to_string(data_len) + " data bytes");
    return false;
  }
  event.offset = start;
  event.event_number = event_number;
  event.utime_us = timestamp;
  event.channel = std::move(channel);
  event.data.resize(static_cast<std::size_t>(data_len));
  if (!readAt(f_, data_at, event.data.data(), event.data.size())) corrupt(start, event.channel, "read error");
  offset_ = end;
  last_event_number_ = event_number;
  ++events_read_;
  return true;
}

std::int64_t LcmLogReader::findNextEventHeader(std::int64_t from, std::int64_t event_number) {
  // A plausible next event: the sync word, event number + 1, a channel length in range and a
  // printable channel name, all inside the file.
  constexpr std::size_t kChunk = 1 << 16;
  std::vector<std::uint8_t> buf(kChunk + kLcmEventHeaderBytes + kMaxLcmChannelChars);
  for (std::int64_t at = from; at < size_; at += static_cast<std::int64_t>(kChunk)) {
    const auto n = static_cast<std::size_t>(std::min<std::int64_t>(static_cast<std::int64_t>(buf.size()), size_ - at));
    if (!readAt(f_, at, buf.data(), n)) return -1;
    for (std::size_t i = 0; i + kLcmEventHeaderBytes <= n && i < kChunk; ++i) {
      if (!std::equal(kSync.begin(), kSync.end(), buf.begin() + static_cast<std::ptrdiff_t>(i))) continue;
      const auto number = static_cast<std::int64_t>(bigEndian(&buf[i + 4], 8));
      const auto channel_len = static_cast<std::int32_t>(bigEndian(&buf[i + 20], 4));
      if (number != event_number + 1 || channel_len < 1 || channel_len > kMaxLcmChannelChars) continue;
      if (i + kLcmEventHeaderBytes + static_cast<std::size_t>(channel_len) > n) continue;
      const auto* name = &buf[i + kLcmEventHeaderBytes];
      if (std::all_of(name, name + channel_len, printable)) return at + static_cast<std::int64_t>(i);
    }
  }
  return -1;
}

// --- run-log reader --------------------------------------------------------------------------

RunLogReader::RunLogReader(const std::filesystem::path& file, RunLogReaderOptions options)
    : raw_(file), options_(options) {}

namespace {

template <class Message>
Message decodeChecked(const LcmLogEvent& event, const std::filesystem::path& file) {
  Message message = decodeEvent<Message>(event, file);
  try {
    if constexpr (std::is_same_v<Message, fullarm_lcm::minima_set_t>) {
      checkFragment(message);
    } else if constexpr (!std::is_same_v<Message, fullarm_lcm::run_header_t>) {
      (void)fromMessage(message);
    }
  } catch (const RecordError& e) {
    throw RunLogError(file.string() + ": corrupt LCM log at byte offset " + std::to_string(event.offset) +
                          " (channel " + event.channel + "): " + e.what(),
                      event.offset, event.channel);
  }
  return message;
}

}  // namespace

bool RunLogReader::next(RunLogEntry& entry) {
  while (raw_.next(entry.event)) {
    const std::string& c = entry.event.channel;
    const std::filesystem::path& file = raw_.file();
    if (c == channel::kJointState) {
      entry.message = decodeChecked<fullarm_lcm::joint_state_t>(entry.event, file);
    } else if (c == channel::kHapticStatus) {
      entry.message = decodeChecked<fullarm_lcm::haptic_status_t>(entry.event, file);
    } else if (c == channel::kValveCommand) {
      entry.message = decodeChecked<fullarm_lcm::valve_command_t>(entry.event, file);
    } else if (c == channel::kMinimaSet) {
      entry.message = decodeChecked<fullarm_lcm::minima_set_t>(entry.event, file);
    } else if (c == channel::kSupervisorEvent) {
      entry.message = decodeChecked<fullarm_lcm::supervisor_event_t>(entry.event, file);
    } else if (c == channel::kRunHeader) {
      entry.message = decodeChecked<fullarm_lcm::run_header_t>(entry.event, file);
    } else if (options_.skip_unknown_channels) {
      ++skipped_;
      continue;
    } else {
      throw RunLogError(file.string() + ": corrupt LCM log at byte offset " + std::to_string(entry.event.offset) +
                            " (channel " + c + "): not a run-log channel",
                        entry.event.offset, c);
    }
    return true;
  }
  return false;
}

}  // namespace fullarm::hil
