#include "server/session_journal.hpp"

#include <sys/stat.h>

#include <filesystem>
#include <iostream>
#include <system_error>

#include "animator/document_changes.hpp"
#include "io/json_parse.hpp"

namespace server {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

animator::SessionWriteError write_error(const std::system_error& e) {
  return animator::SessionWriteError(e.code().value(), e.what());
}

// Applies the changes of one record's payload; "" when it did, else what is wrong with it.
std::string replay(const io::JournalRecord& r,
                   const std::string& source,
                   const core::Model& model,
                   animator::Document& doc,
                   animator::Playback& playback) {
  try {
    const json payload = io::parse_json(r.payload, source, animator::kSessionJsonLimits);
    if (!payload.is_object() || !payload.contains("changes")) {
      return "the payload has no \"changes\" (rule: {\"op\": ..., \"changes\": {...}})";
    }
    animator::apply_document_changes(model, payload["changes"], doc, playback);
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

}  // namespace

std::string SessionJournal::journal_path(const std::string& session_path) {
  return fs::path(session_path).replace_extension(".journal").string();
}

SessionJournal::SessionJournal(std::string session_path,
                               animator::SessionImage durable,
                               const io::JournalContents& contents)
    : session_path_(std::move(session_path)),
      durable_(std::move(durable)),
      writer_(journal_path(session_path_), contents) {}

SessionJournal::~SessionJournal() { wait_for_snapshot(); }

std::unique_ptr<SessionJournal> SessionJournal::start(const std::string& session_path,
                                                      const animator::Session& session) {
  animator::SessionImage image = animator::session_image(session);
  image.journal_seq = 0;
  animator::save_session(image, session_path);
  try {
    // an empty journal: one left under this name is emptied
    return std::unique_ptr<SessionJournal>(
        new SessionJournal(session_path, std::move(image), io::JournalContents{}));
  } catch (const std::system_error& e) {
    throw write_error(e);
  }
}

SessionJournal::Loaded SessionJournal::load(const std::string& session_path, std::ostream& log) {
  std::uint64_t snapshot_seq = 0;
  Loaded out;
  out.session = animator::load_session(session_path, &snapshot_seq);
  // a session file written before they were private (0644) becomes so now
  ::chmod(session_path.c_str(), 0600);
  const std::string path = journal_path(session_path);
  io::JournalContents contents;
  try {
    contents = io::read_journal(path);
  } catch (const std::system_error& e) {
    throw animator::SessionError(e.what());
  }

  animator::Document doc = out.session->document();
  animator::Playback playback = out.session->playback();
  std::uint64_t seq = snapshot_seq;
  for (std::size_t k = 0; k < contents.records.size(); ++k) {
    const io::JournalRecord& r = contents.records[k];
    if (r.seq <= snapshot_seq) continue;  // the snapshot holds it already
    std::string problem = r.seq != seq + 1
                              ? "sequence number " + std::to_string(r.seq) + " follows " +
                                    std::to_string(seq) + " (rule: one more than the last)"
                              : replay(r, path, out.session->model(), doc, playback);
    if (!problem.empty()) {
      contents.problem = "record at byte " + std::to_string(r.offset) + ": " + problem;
      contents.torn_tail = false;
      contents.records.resize(k);
      contents.valid_bytes = r.offset;
      break;
    }
    seq = r.seq;
    ++out.replayed;
  }
  if (contents.torn_tail) {
    log << "pindrag serve: " << path << ": " << contents.problem
        << "; dropped (an append cut short, never acknowledged)\n";
  } else if (!contents.problem.empty()) {
    const std::string kept = path + ".damaged";
    std::error_code ec;
    fs::copy_file(path, kept, fs::copy_options::overwrite_existing, ec);
    log << "pindrag serve: " << path << ": " << contents.problem
        << "; the records from there on are not replayed"
        << (ec ? " (the journal could not be kept: " + ec.message() + ")"
               : "; the journal as it was is kept as " + kept)
        << "\n";
  }
  out.session->restore(doc, playback);
  animator::SessionImage image = animator::session_image(*out.session);
  image.journal_seq = seq;
  try {
    out.journal.reset(new SessionJournal(session_path, std::move(image), contents));
  } catch (const std::system_error& e) {
    throw write_error(e);
  }
  return out;
}

bool SessionJournal::record(const animator::Session& session, const json& op) {
  json changes = animator::document_changes(*durable_.model, durable_.document, durable_.playback,
                                            session.document(), session.playback());
  if (changes.empty()) return false;
  const std::uint64_t seq = durable_.journal_seq + 1;
  const std::string payload = json{{"op", op}, {"changes", std::move(changes)}}.dump(
      -1, ' ', false, json::error_handler_t::replace);
  try {
    std::lock_guard lock(file_mutex_);
    writer_.append(seq, payload);
  } catch (const std::system_error& e) {
    throw write_error(e);
  }
  durable_.document = session.document();
  durable_.playback = session.playback();
  durable_.journal_seq = seq;
  return true;
}

std::size_t SessionJournal::journal_records() const {
  std::lock_guard lock(file_mutex_);
  return writer_.records();
}

std::uint64_t SessionJournal::journal_bytes() const {
  std::lock_guard lock(file_mutex_);
  return writer_.bytes();
}

bool SessionJournal::snapshot_if_due(bool settled) {
  if (snapshot_running_) return false;
  wait_for_snapshot();  // a finished one: join its thread
  std::size_t records = 0;
  std::uint64_t bytes = 0;
  {
    std::lock_guard lock(file_mutex_);
    records = writer_.records();
    bytes = writer_.bytes();
  }
  if (records == 0) return false;
  const auto now = std::chrono::steady_clock::now();
  const bool waited = now - last_snapshot_ >= kSnapshotInterval;
  // after a failed snapshot (a full disk) the next one waits too, whatever the journal holds
  const bool large = records >= kSnapshotRecords || bytes >= kSnapshotBytes;
  const bool due = (large && (waited || !snapshot_failed_)) || (settled && waited);
  if (!due) return false;
  last_snapshot_ = now;
  snapshot_running_ = true;
  snapshot_thread_ = std::thread([this, image = durable_] {
    snapshot_failed_ = false;
    try {
      write_snapshot(image);
    } catch (const std::exception& e) {
      snapshot_failed_ = true;
      // nothing is lost: the journal still holds every record
      std::cerr << "pindrag serve: " << session_path_ << ": snapshot not written: " << e.what()
                << "\n";
    }
    snapshot_running_ = false;
  });
  return true;
}

void SessionJournal::snapshot_now() {
  wait_for_snapshot();
  last_snapshot_ = std::chrono::steady_clock::now();
  write_snapshot(durable_);
}

void SessionJournal::write_snapshot(const animator::SessionImage& image) {
  animator::save_session(image, session_path_);
  std::lock_guard lock(file_mutex_);
  try {
    writer_.drop_through(image.journal_seq);
  } catch (const std::system_error& e) {
    throw write_error(e);
  }
  ++snapshots_;
}

void SessionJournal::wait_for_snapshot() {
  if (snapshot_thread_.joinable()) snapshot_thread_.join();
}

}  // namespace server
