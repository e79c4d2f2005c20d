// An append-only file of checksummed records: the write-ahead log beside a snapshot file. Each
// record is durable (fdatasync) when append() returns; a record cut short by a crash is
// recognised and dropped when the file is read back; once a snapshot holds the records up to a
// sequence number, drop_through() removes them.
//
// Layout: records back to back, each a 20-byte header and the payload:
//   "PDJ1" | payload length (u32 LE) | sequence number (u64 LE)
//   | CRC-32C of the length, sequence number and payload (u32 LE) | payload
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace io {

/// Bytes of a record header.
constexpr std::size_t kJournalHeaderBytes = 20;
/// Largest payload of one record; a header that claims more is damaged.
constexpr std::uint32_t kMaxJournalPayloadBytes = std::uint32_t{1} << 30;

struct JournalRecord {
  std::uint64_t seq = 0;
  std::uint64_t offset = 0;  // of its header in the file
  std::string payload;
};

/// What reading a journal found: every record before the first incomplete or damaged one.
struct JournalContents {
  std::vector<JournalRecord> records;
  std::uint64_t valid_bytes = 0;  // end of the last good record
  std::uint64_t file_bytes = 0;
  /// Why reading stopped before the end of the file ("" when it did not): "record at byte N:
  /// <rule>".
  std::string problem;
  /// The problem is only a last record cut short (what a crash during an append leaves).
  bool torn_tail = false;
};

/// CRC-32C (Castagnoli) of `bytes`, continuing from `crc` (0 to start).
std::uint32_t crc32c(std::string_view bytes, std::uint32_t crc = 0);

/// The bytes of one record.
std::string journal_record(std::uint64_t seq, std::string_view payload);

/// Reads records from the bytes of a journal.
JournalContents parse_journal(std::string_view bytes);
/// Reads the journal at `path`; a missing file reads as empty.
/// @throws std::system_error naming the path
JournalContents read_journal(const std::string& path);

/// A journal open for appending. Not thread-safe: one caller at a time.
class JournalWriter {
 public:
  /// Opens `path` for appending after `contents` (as read_journal found it): a missing file is
  /// created (mode 0600, its folder fsync'd), and bytes after contents.valid_bytes (a torn
  /// record) are cut off. @throws std::system_error naming the path and the step
  JournalWriter(std::string path, const JournalContents& contents);
  ~JournalWriter();
  JournalWriter(const JournalWriter&) = delete;
  JournalWriter& operator=(const JournalWriter&) = delete;

  /// Appends one record and syncs it (fdatasync). On failure nothing was appended: the file is
  /// cut back to its previous end (or the next append overwrites what a failed one left).
  /// @throws std::system_error naming the path and the step (write, fdatasync)
  void append(std::uint64_t seq, std::string_view payload);
  /// Drops every record whose sequence number is <= `seq`: the file becomes empty when none is
  /// left, else the remaining records are written to a new file renamed over it. A crash leaves
  /// the old file or the new one. @throws std::system_error; the journal is unchanged then
  void drop_through(std::uint64_t seq);

  const std::string& path() const { return path_; }
  std::uint64_t bytes() const { return end_; }
  std::size_t records() const { return index_.size(); }

 private:
  void replace_file(const std::string& bytes);

  std::string path_;
  int fd_ = -1;
  std::uint64_t end_ = 0;                                       // end of the last good record
  std::vector<std::pair<std::uint64_t, std::uint64_t>> index_;  // (seq, offset) of each record
  bool tail_dirty_ = false;  // a failed append may have left bytes after end_
};

}  // namespace io
