#include "io/journal_file.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <system_error>

#include "io/read_file.hpp"

namespace io {

namespace {

constexpr char kMagic[4] = {'P', 'D', 'J', '1'};

constexpr std::array<std::uint32_t, 256> crc32c_table() {
  std::array<std::uint32_t, 256> table{};
  for (std::uint32_t i = 0; i < 256; ++i) {
    std::uint32_t c = i;
    for (int k = 0; k < 8; ++k) c = (c & 1) ? (c >> 1) ^ 0x82F63B78u : c >> 1;  // reflected
    table[i] = c;
  }
  return table;
}
constexpr std::array<std::uint32_t, 256> kCrcTable = crc32c_table();

void put_u32(std::string& out, std::uint32_t v) {
  for (int k = 0; k < 4; ++k) out += static_cast<char>((v >> (8 * k)) & 0xFF);
}
void put_u64(std::string& out, std::uint64_t v) {
  for (int k = 0; k < 8; ++k) out += static_cast<char>((v >> (8 * k)) & 0xFF);
}
std::uint64_t get_le(std::string_view bytes, std::size_t at, int n) {
  std::uint64_t v = 0;
  for (int k = n - 1; k >= 0; --k) v = (v << 8) | static_cast<unsigned char>(bytes[at + k]);
  return v;
}

// the checksum covers the length and sequence fields (header bytes 4..15) and the payload
std::uint32_t record_crc(std::string_view length_and_seq, std::string_view payload) {
  return crc32c(payload, crc32c(length_and_seq));
}

std::system_error file_error(int err, const std::string& path, const std::string& what) {
  return std::system_error(err, std::generic_category(), path + ": " + what);
}

void sync_folder(const std::string& path) {
  const std::filesystem::path dir = std::filesystem::path(path).parent_path();
  const int dfd = ::open(dir.empty() ? "." : dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dfd < 0) return;
  ::fsync(dfd);
  ::close(dfd);
}

bool all_zero(std::string_view bytes) {
  for (char c : bytes) {
    if (c != 0) return false;
  }
  return true;
}

}  // namespace

std::uint32_t crc32c(std::string_view bytes, std::uint32_t crc) {
  crc = ~crc;
  for (char b : bytes) crc = kCrcTable[(crc ^ static_cast<unsigned char>(b)) & 0xFF] ^ (crc >> 8);
  return ~crc;
}

std::string journal_record(std::uint64_t seq, std::string_view payload) {
  std::string out(kMagic, 4);
  out.reserve(kJournalHeaderBytes + payload.size());
  put_u32(out, static_cast<std::uint32_t>(payload.size()));
  put_u64(out, seq);
  put_u32(out, record_crc(std::string_view(out).substr(4, 12), payload));
  out.append(payload);
  return out;
}

JournalContents parse_journal(std::string_view bytes) {
  JournalContents out;
  out.file_bytes = bytes.size();
  std::size_t at = 0;
  auto stop = [&](const std::string& rule, bool torn) {
    out.problem = "record at byte " + std::to_string(at) + ": " + rule;
    out.torn_tail = torn;
  };
  while (at < bytes.size()) {
    const std::string_view rest = bytes.substr(at);
    if (rest.size() < kJournalHeaderBytes) {
      stop("cut short in its header (" + std::to_string(rest.size()) + " of " +
               std::to_string(kJournalHeaderBytes) + " bytes)",
           true);
      break;
    }
    if (std::memcmp(rest.data(), kMagic, 4) != 0) {
      // a crash can leave the file longer than what was written, filled with zeros
      stop(all_zero(rest) ? "zeros to the end of the file" : "no record header (rule: \"PDJ1\")",
           all_zero(rest));
      break;
    }
    const std::uint64_t length = get_le(rest, 4, 4);
    if (length > kMaxJournalPayloadBytes) {
      stop("claims " + std::to_string(length) + " bytes (rule: at most " +
               std::to_string(kMaxJournalPayloadBytes) + ")",
           false);
      break;
    }
    if (rest.size() < kJournalHeaderBytes + length) {
      stop("cut short (" + std::to_string(rest.size() - kJournalHeaderBytes) + " of " +
               std::to_string(length) + " payload bytes)",
           true);
      break;
    }
    const std::string_view payload = rest.substr(kJournalHeaderBytes, length);
    if (record_crc(rest.substr(4, 12), payload) != get_le(rest, 16, 4)) {
      stop("checksum mismatch (rule: CRC-32C of the length, sequence number and payload)",
           rest.size() == kJournalHeaderBytes + length);
      break;
    }
    out.records.push_back(JournalRecord{get_le(rest, 8, 8), at, std::string(payload)});
    at += kJournalHeaderBytes + length;
    out.valid_bytes = at;
  }
  return out;
}

JournalContents read_journal(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) return {};
  std::string bytes;
  try {
    bytes = read_file(path, std::uint64_t{1} << 40, "a journal");
  } catch (const FileError& e) {
    throw std::system_error(EIO, std::generic_category(), e.what());
  }
  return parse_journal(bytes);
}

JournalWriter::JournalWriter(std::string path, const JournalContents& contents)
    : path_(std::move(path)), end_(contents.valid_bytes) {
  bool created = true;
  fd_ = ::open(path_.c_str(), O_RDWR | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0600);
  if (fd_ < 0 && errno == EEXIST) {
    created = false;
    fd_ = ::open(path_.c_str(), O_RDWR | O_NOFOLLOW | O_CLOEXEC);
  }
  if (fd_ < 0) throw file_error(errno, path_, "cannot open the journal");
  if (created) sync_folder(path_);
  struct stat st {};
  if (::fstat(fd_, &st) != 0) {
    const int err = errno;
    ::close(fd_);
    throw file_error(err, path_, "cannot stat the journal");
  }
  if (static_cast<std::uint64_t>(st.st_size) != end_) {
    // a torn record (or damage reported by the reader) after the last good record
    if (::ftruncate(fd_, static_cast<off_t>(end_)) != 0 || ::fdatasync(fd_) != 0) {
      const int err = errno;
      ::close(fd_);
      throw file_error(err, path_, "cannot cut the journal back to its last good record");
    }
  }
  for (const JournalRecord& r : contents.records) index_.emplace_back(r.seq, r.offset);
}

JournalWriter::~JournalWriter() {
  if (fd_ >= 0) ::close(fd_);
}

void JournalWriter::append(std::uint64_t seq, std::string_view payload) {
  if (payload.size() > kMaxJournalPayloadBytes) {
    throw file_error(EFBIG, path_,
                     "a record of " + std::to_string(payload.size()) + " bytes (rule: at most " +
                         std::to_string(kMaxJournalPayloadBytes) + ")");
  }
  if (tail_dirty_) {
    if (::ftruncate(fd_, static_cast<off_t>(end_)) != 0) {
      throw file_error(errno, path_, "cannot remove what a failed append left");
    }
    tail_dirty_ = false;
  }
  const std::string record = journal_record(seq, payload);
  auto fail = [&](const std::string& what) {
    const int err = errno ? errno : EIO;
    tail_dirty_ = ::ftruncate(fd_, static_cast<off_t>(end_)) != 0;
    throw file_error(err, path_, what);
  };
  std::size_t done = 0;
  while (done < record.size()) {
    errno = 0;
    const ssize_t n =
        ::pwrite(fd_, record.data() + done, record.size() - done, static_cast<off_t>(end_ + done));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) fail("write failed");
    done += static_cast<std::size_t>(n);
  }
  errno = 0;
  if (::fdatasync(fd_) != 0) fail("fdatasync failed");
  index_.emplace_back(seq, end_);
  end_ += record.size();
}

void JournalWriter::drop_through(std::uint64_t seq) {
  std::size_t first_kept = 0;
  while (first_kept < index_.size() && index_[first_kept].first <= seq) ++first_kept;
  if (first_kept == 0) return;
  if (first_kept == index_.size()) {
    if (::ftruncate(fd_, 0) != 0 || ::fdatasync(fd_) != 0) {
      throw file_error(errno, path_, "cannot empty the journal");
    }
    index_.clear();
    end_ = 0;
    tail_dirty_ = false;
    return;
  }
  // the records after `seq`, moved to the front of a new file
  const std::uint64_t from = index_[first_kept].second;
  std::string kept(static_cast<std::size_t>(end_ - from), '\0');
  std::size_t done = 0;
  while (done < kept.size()) {
    const ssize_t n =
        ::pread(fd_, kept.data() + done, kept.size() - done, static_cast<off_t>(from + done));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) throw file_error(n < 0 ? errno : EIO, path_, "cannot read the journal back");
    done += static_cast<std::size_t>(n);
  }
  replace_file(kept);
  index_.erase(index_.begin(), index_.begin() + static_cast<std::ptrdiff_t>(first_kept));
  for (auto& entry : index_) entry.second -= from;
  end_ -= from;
  tail_dirty_ = false;
}

// a temporary file beside the journal holding `bytes`, synced and renamed over it; the open
// descriptor of the temporary file becomes the journal's, so no append can reach the old one
void JournalWriter::replace_file(const std::string& bytes) {
  const std::string temp = path_ + ".rewrite";
  const int fd = ::open(temp.c_str(), O_RDWR | O_CREAT | O_TRUNC | O_NOFOLLOW | O_CLOEXEC, 0600);
  if (fd < 0) throw file_error(errno, temp, "cannot create the rewritten journal");
  auto fail = [&](const std::string& what) {
    const int err = errno ? errno : EIO;
    ::close(fd);
    ::unlink(temp.c_str());
    throw file_error(err, temp, what);
  };
  std::size_t done = 0;
  while (done < bytes.size()) {
    errno = 0;
    const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) fail("write failed");
    done += static_cast<std::size_t>(n);
  }
  errno = 0;
  if (::fsync(fd) != 0) fail("fsync failed");
  if (::rename(temp.c_str(), path_.c_str()) != 0) fail("cannot rename it over " + path_);
  sync_folder(path_);
  ::close(fd_);
  fd_ = fd;
}

}  // namespace io
