// The bytes of a C3D file under io/c3d.hpp: 512-byte blocks, numbers in the format of the
// processor that wrote them, and the parameter section (groups and their parameters). Internal to
// io/c3d*.cpp. Format facts from the C3D User Guide (c3d.org): "The Header Section", "The
// Parameter Section", "Group Format", "Parameter Format".
#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace io::c3d_detail {

/// A C3D file is a sequence of 512-byte blocks, numbered from 1 (block 1 is the header).
constexpr std::size_t kBlockBytes = 512;

/// Byte 4 of the parameter section: 83 + the processor type.
enum class Processor : std::uint8_t { kIntel = 84, kDec = 85, kMips = 86 };

/// Throws io::C3dError("<source>: <what>").
[[noreturn]] void fail(const std::string& source, const std::string& what);

/// File text fit for a message: quoted, control and non-ASCII bytes as '?', at most 40 bytes.
std::string shown_text(std::string_view text);

/// A number for a message: up to 9 significant digits, no trailing zeros ("0", "120", "NaN").
std::string number_text(double v);

/// Blocks that `bytes` bytes occupy (the last one may be partial).
std::size_t blocks_in(std::size_t bytes);

// Little-endian 16-bit words: Intel and DEC store integers alike. Callers check the bounds.
std::uint16_t u16(std::string_view bytes, std::size_t at);
std::int16_t i16(std::string_view bytes, std::size_t at);

/// VAX F_floating from its two 16-bit words in file order. The first holds the sign (bit 15), the
/// exponent e (bits 14–7, excess 128) and the top 7 fraction bits; the second the low 16. The
/// value is 0.1f × 2^(e − 128) (a hidden 1 right after the binary point), which is the IEEE
/// reading of the word-swapped bits divided by 4. e = 0 is zero, or with the sign set a reserved
/// operand (NaN here).
double vax_f(std::uint16_t first, std::uint16_t second);

/// The 32-bit float at `at`: IEEE 754 little-endian (Intel) or VAX F_floating (DEC).
double real(std::string_view bytes, std::size_t at, Processor processor);

/// One parameter as stored: its data stays in the file's bytes.
struct Parameter {
  std::string group;      // group name, upper case
  std::string name;       // parameter name, upper case
  int type = 0;           // bytes per element: -1 char, 1 byte, 2 int16, 4 float
  std::vector<int> dims;  // 0 to 7 dimensions of 0 to 255 (none: a scalar)
  std::string_view data;  // |type| × product(dims) bytes
  std::string field() const { return group + ":" + name; }
  std::size_t elements() const;  // product(dims), 1 for a scalar
};

/// The parameter section, walked once along its chain of next-record offsets, with typed reads
/// that name GROUP:NAME and the rule in their errors. A parameter whose group is absent is
/// dropped; of two with the same names the first counts.
class Parameters {
 public:
  /// Walks the section starting at 1-based `block` (the caller checked that its 4-byte header
  /// lies inside `file`). Refuses processors other than Intel and DEC.
  Parameters(std::string_view file, std::size_t block, const std::string& source);

  Processor processor() const { return processor_; }
  std::size_t first_block() const { return first_block_; }
  std::size_t block_count() const { return block_count_; }

  const Parameter* find(std::string_view group, std::string_view name) const;
  /// The first element as a finite number (type 1 unsigned, 2 signed, 4 float); nullopt when
  /// the parameter is absent.
  std::optional<double> number(std::string_view group, std::string_view name) const;
  /// A whole number ≥ 0: type 1 or 2 read unsigned (C3D counts go to 65535), or a whole float.
  std::optional<std::int64_t> count(std::string_view group, std::string_view name) const;
  /// A 32-bit count stored as two unsigned 16-bit words, least significant first (TRIAL group),
  /// or as one count().
  std::optional<std::int64_t> long_count(std::string_view group, std::string_view name) const;
  /// A char array: the first dimension is the length of each string, the rest their number;
  /// trailing blanks and NULs are trimmed.
  std::optional<std::vector<std::string>> strings(std::string_view group,
                                                  std::string_view name) const;

 private:
  const Parameter& numeric(const Parameter& p) const;
  double element(const Parameter& p, std::size_t i) const;

  std::string source_;
  Processor processor_ = Processor::kIntel;
  std::size_t first_block_ = 0;
  std::size_t block_count_ = 0;
  std::vector<Parameter> params_;
  std::map<std::string, std::size_t> index_;  // "GROUP:NAME" → index in params_
};

}  // namespace io::c3d_detail
