// Tests for io/journal_file.hpp: records read back as written, a torn last record dropped, a
// checksum mismatch detected, appends that fail leave nothing behind, records dropped after a
// snapshot, and the file private to its owner.
#include "io/journal_file.hpp"

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "io/read_file.hpp"

namespace {

namespace fs = std::filesystem;
using io::JournalContents;
using io::JournalWriter;

std::string temp_path(const std::string& name) {
  return (fs::temp_directory_path() /
          ("pindrag-journal-test-" + std::to_string(::getpid()) + "-" + name))
      .string();
}

std::string bytes_of(const std::string& path) { return io::read_file(path, 1 << 20); }

void write_bytes(const std::string& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary | std::ios::trunc) << bytes;
}

// Holds the process's file size limit at `bytes` (writes beyond fail with EFBIG, SIGXFSZ
// ignored) until it goes out of scope.
class FileSizeLimit {
 public:
  explicit FileSizeLimit(rlim_t bytes) {
    ::getrlimit(RLIMIT_FSIZE, &saved_);
    old_handler_ = ::signal(SIGXFSZ, SIG_IGN);
    rlimit limit = saved_;
    limit.rlim_cur = bytes;
    ::setrlimit(RLIMIT_FSIZE, &limit);
  }
  ~FileSizeLimit() {
    ::setrlimit(RLIMIT_FSIZE, &saved_);
    ::signal(SIGXFSZ, old_handler_);
  }

 private:
  rlimit saved_{};
  sighandler_t old_handler_{};
};

TEST(JournalFile, RecordsReadBackInOrderWithTheirOffsets) {
  const std::string a = io::journal_record(1, "first");
  const std::string b = io::journal_record(2, "");
  const std::string c = io::journal_record(7, std::string(1000, 'x'));
  const JournalContents j = io::parse_journal(a + b + c);
  ASSERT_EQ(j.records.size(), 3u);
  EXPECT_EQ(j.records[0].seq, 1u);
  EXPECT_EQ(j.records[0].payload, "first");
  EXPECT_EQ(j.records[1].offset, a.size());
  EXPECT_EQ(j.records[1].payload, "");
  EXPECT_EQ(j.records[2].seq, 7u);
  EXPECT_EQ(j.records[2].payload, std::string(1000, 'x'));
  EXPECT_EQ(j.valid_bytes, a.size() + b.size() + c.size());
  EXPECT_TRUE(j.problem.empty());
  // the CRC-32C check value of "123456789"
  EXPECT_EQ(io::crc32c("123456789"), 0xE3069283u);
}

TEST(JournalFile, ATornLastRecordIsDroppedAndReportedAsTorn) {
  const std::string a = io::journal_record(1, "kept");
  const std::string b = io::journal_record(2, "cut short by a crash");
  for (std::size_t cut = 1; cut < b.size(); ++cut) {
    const JournalContents j = io::parse_journal(a + b.substr(0, cut));
    ASSERT_EQ(j.records.size(), 1u) << cut;
    EXPECT_EQ(j.records[0].payload, "kept");
    EXPECT_EQ(j.valid_bytes, a.size());
    EXPECT_TRUE(j.torn_tail) << cut << ": " << j.problem;
    EXPECT_EQ(j.problem.rfind("record at byte " + std::to_string(a.size()) + ": cut short", 0), 0u)
        << j.problem;
  }
  // a file that grew with zeros past its last write (a crash before the data reached the disk)
  const JournalContents zeros = io::parse_journal(a + std::string(64, '\0'));
  EXPECT_EQ(zeros.records.size(), 1u);
  EXPECT_TRUE(zeros.torn_tail) << zeros.problem;
}

TEST(JournalFile, AChecksumMismatchIsDetectedAndStopsTheReading) {
  const std::string a = io::journal_record(1, "good");
  std::string b = io::journal_record(2, "flipped");
  const std::string c = io::journal_record(3, "after the damage");
  b[io::kJournalHeaderBytes + 2] ^= 0x01;  // one bit of the payload
  const JournalContents j = io::parse_journal(a + b + c);
  ASSERT_EQ(j.records.size(), 1u);
  EXPECT_EQ(j.valid_bytes, a.size());
  EXPECT_FALSE(j.torn_tail);
  EXPECT_EQ(j.problem, "record at byte " + std::to_string(a.size()) +
                           ": checksum mismatch (rule: CRC-32C of the length, sequence number "
                           "and payload)");
  // a flipped sequence number is caught as well, and so is a header that is not one
  std::string d = io::journal_record(2, "seq");
  d[8] ^= 0x04;
  EXPECT_NE(io::parse_journal(a + d).problem.find("checksum mismatch"), std::string::npos);
  const JournalContents junk = io::parse_journal(a + "garbage that is not a record");
  EXPECT_FALSE(junk.torn_tail);
  EXPECT_NE(junk.problem.find("no record header"), std::string::npos) << junk.problem;
  // a length beyond the cap is damage, not a record to allocate for
  std::string huge = io::journal_record(2, "x");
  huge[7] = static_cast<char>(0x7F);
  EXPECT_NE(io::parse_journal(a + huge).problem.find("claims"), std::string::npos);
}

TEST(JournalFile, AppendsAreReadBackAndATornTailIsCutWhenReopened) {
  const std::string path = temp_path("append");
  fs::remove(path);
  {
    JournalWriter w(path, io::read_journal(path));
    w.append(1, "one");
    w.append(2, "two");
    EXPECT_EQ(w.records(), 2u);
  }
  struct stat st {};
  ASSERT_EQ(::stat(path.c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 0777, 0600u);
  // a crash in the middle of the third append
  const std::string third = io::journal_record(3, "three");
  write_bytes(path, bytes_of(path) + third.substr(0, third.size() - 2));
  JournalContents j = io::read_journal(path);
  EXPECT_TRUE(j.torn_tail);
  ASSERT_EQ(j.records.size(), 2u);
  {
    JournalWriter w(path, j);  // cuts the torn record off
    w.append(3, "three again");
  }
  j = io::read_journal(path);
  EXPECT_TRUE(j.problem.empty()) << j.problem;
  ASSERT_EQ(j.records.size(), 3u);
  EXPECT_EQ(j.records[2].payload, "three again");
  fs::remove(path);
}

TEST(JournalFile, DroppingRecordsKeepsTheLaterOnes) {
  const std::string path = temp_path("drop");
  fs::remove(path);
  JournalWriter w(path, io::read_journal(path));
  for (std::uint64_t seq = 1; seq <= 5; ++seq) w.append(seq, "record " + std::to_string(seq));
  w.drop_through(0);  // nothing at or below 0
  EXPECT_EQ(w.records(), 5u);
  w.drop_through(3);
  EXPECT_EQ(w.records(), 2u);
  w.append(6, "record 6");
  JournalContents j = io::read_journal(path);
  ASSERT_EQ(j.records.size(), 3u);
  EXPECT_EQ(j.records[0].seq, 4u);
  EXPECT_EQ(j.records[0].offset, 0u);
  EXPECT_EQ(j.records[2].payload, "record 6");
  struct stat st {};
  ASSERT_EQ(::stat(path.c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 0777, 0600u);  // the rewritten file too
  w.drop_through(6);
  EXPECT_EQ(w.bytes(), 0u);
  EXPECT_EQ(fs::file_size(path), 0u);
  fs::remove(path);
}

TEST(JournalFile, AFailedAppendLeavesNothingAndTheNextOneWorks) {
  const std::string path = temp_path("full");
  fs::remove(path);
  JournalWriter w(path, io::read_journal(path));
  w.append(1, "fits");
  const std::uint64_t size = fs::file_size(path);
  {
    // room for the header and part of the payload: the write stops half way with EFBIG
    FileSizeLimit limit(size + io::kJournalHeaderBytes + 10);
    try {
      w.append(2, std::string(100, 'y'));
      ADD_FAILURE() << "the append past the file size limit succeeded";
    } catch (const std::system_error& e) {
      EXPECT_EQ(e.code().value(), EFBIG);
      EXPECT_NE(std::string(e.what()).find(path + ": write failed"), std::string::npos) << e.what();
    }
  }
  EXPECT_EQ(fs::file_size(path), size);  // cut back: no half record
  EXPECT_EQ(w.records(), 1u);
  w.append(2, "after the disk has room again");
  const JournalContents j = io::read_journal(path);
  EXPECT_TRUE(j.problem.empty()) << j.problem;
  ASSERT_EQ(j.records.size(), 2u);
  EXPECT_EQ(j.records[1].payload, "after the disk has room again");
  fs::remove(path);
}

}  // namespace
