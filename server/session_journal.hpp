// Write-ahead persistence of one session (docs/protocol.md "Durability"). Two files in the data
// folder, both mode 0600: the snapshot <id>.json (a session file, animator/session_file.hpp) and
// the journal <id>.journal (io/journal_file.hpp), one record per change since the snapshot.
//
// record() returns once the change is on disk (fdatasync): the actor acknowledges an edit only
// then, and takes the edit back when it throws. A record holds the message that made the change
// and the change itself (animator/document_changes.hpp), so replaying it needs no solver and
// reproduces the state exactly. Snapshots are written on a thread of their own from the state
// the journal has reached (never on the path of an acknowledgement); the records a snapshot holds
// are dropped after it is renamed into place. Loading reads the snapshot and replays the records
// after its `journal_seq`, so a crash between the two steps replays nothing twice.
//
// Thread contract: one thread (the session's actor) calls every function; the snapshot thread
// shares only the journal file, under a mutex.
#pragma once

#include <atomic>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <ostream>
#include <string>
#include <thread>

#include "animator/session.hpp"
#include "animator/session_file.hpp"
#include "io/journal_file.hpp"

namespace server {

class SessionJournal {
 public:
  /// A snapshot starts when the figure settles and the previous one started at least
  /// kSnapshotInterval ago, and at once when the journal holds kSnapshotRecords records or
  /// kSnapshotBytes bytes (after a failed one, only once kSnapshotInterval has passed).
  static constexpr std::chrono::seconds kSnapshotInterval{5};
  static constexpr std::size_t kSnapshotRecords = 200;
  static constexpr std::uint64_t kSnapshotBytes = std::uint64_t{16} << 20;

  /// <dir>/<id>.journal beside the snapshot <dir>/<id>.json.
  static std::string journal_path(const std::string& session_path);

  /// Saves a new session: its snapshot now and an empty journal.
  /// @throws animator::SessionWriteError naming the file
  static std::unique_ptr<SessionJournal> start(const std::string& session_path,
                                               const animator::Session& session);

  struct Loaded {
    std::unique_ptr<animator::Session> session;
    std::unique_ptr<SessionJournal> journal;
    std::uint64_t replayed = 0;  // records applied over the snapshot
  };
  /// A saved session: the snapshot with the journal's later records replayed. A torn last
  /// record (a crash during its append: never acknowledged) is dropped; a damaged one stops the
  /// replay, and the journal is kept as <id>.journal.damaged before it is cut there. Both are
  /// reported to `log`.
  /// @throws animator::SessionError when the snapshot cannot be read (SessionWriteError when the
  ///         journal cannot be opened)
  static Loaded load(const std::string& session_path, std::ostream& log);

  ~SessionJournal();  // waits for a snapshot being written
  SessionJournal(const SessionJournal&) = delete;
  SessionJournal& operator=(const SessionJournal&) = delete;

  /// Makes what the session's document and playback state changed since the last record
  /// durable: appends one record (with `op`, the message that made the change) and syncs it.
  /// Returns false when nothing saved changed (nothing is written then).
  /// @throws animator::SessionWriteError; nothing was recorded, and document() and playback()
  ///         are still what the disk holds
  bool record(const animator::Session& session, const nlohmann::json& op);
  /// The state the disk holds: the snapshot and every record.
  const animator::Document& document() const { return durable_.document; }
  const animator::Playback& playback() const { return durable_.playback; }
  /// Sequence number of the last record (that of the snapshot when none followed it).
  std::uint64_t seq() const { return durable_.journal_seq; }

  /// Starts writing a snapshot on a thread of its own when one is due (see kSnapshotInterval;
  /// `settled`: the figure has come to rest) and none is being written. Returns whether it did.
  bool snapshot_if_due(bool settled);
  /// Writes a snapshot on the calling thread (after any being written) and drops the records it
  /// holds. @throws animator::SessionWriteError
  void snapshot_now();
  /// Snapshots written since this journal was opened.
  std::uint64_t snapshots() const { return snapshots_; }
  bool snapshot_running() const { return snapshot_running_; }
  /// What the journal file holds now.
  std::size_t journal_records() const;
  std::uint64_t journal_bytes() const;

 private:
  SessionJournal(std::string session_path,
                 animator::SessionImage durable,
                 const io::JournalContents& contents);
  void write_snapshot(const animator::SessionImage& image);
  void wait_for_snapshot();

  const std::string session_path_;
  animator::SessionImage durable_;  // journal_seq: the last record

  mutable std::mutex file_mutex_;  // guards writer_ (the snapshot thread drops records)
  io::JournalWriter writer_;

  std::thread snapshot_thread_;
  std::atomic<bool> snapshot_running_{false};
  std::atomic<bool> snapshot_failed_{false};  // the last one: then the next waits its interval
  std::atomic<std::uint64_t> snapshots_{0};
  std::chrono::steady_clock::time_point last_snapshot_{};
};

}  // namespace server
