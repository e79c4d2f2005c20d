// libFuzzer harness for io/c3d.hpp. Any input must parse or fail with io::C3dError; nothing else
// may escape, crash, hang, leak or allocate beyond what the input can hold. A trial that parses
// has sizes that agree (frames × points samples, one label per point), finite positions that are
// zero where a sample is missing, a positive finite rate and one of the three units.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <string_view>

#include "io/c3d.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  io::C3dTrial t;
  try {
    t = io::parse_c3d(bytes, "fuzz.c3d");
  } catch (const io::C3dError&) {
    return 0;
  }
  const auto samples = static_cast<std::size_t>(t.frame_count()) * t.labels.size();
  if (t.frame_count() < 0 || t.frame_count() > io::kMaxC3dFrames) std::abort();
  if (t.positions.size() != samples || t.present.size() != samples) std::abort();
  // every sample comes from 8 or 16 bytes of the input
  if (samples > size / 8) std::abort();
  if (!(t.rate_hz > 0 && t.rate_hz <= io::kMaxC3dRateHz)) std::abort();
  if (t.to_metres != 1e-3 && t.to_metres != 1e-2 && t.to_metres != 1.0) std::abort();
  for (std::size_t i = 0; i < samples; ++i) {
    if (t.present[i] > 1 || !t.positions[i].allFinite()) std::abort();
    if (t.present[i] == 0 && !t.positions[i].isZero(0)) std::abort();
  }
  // find() on up to 256 labels spread over the list (each call is a linear scan)
  const int step = 1 + t.point_count() / 256;
  for (int p = 0; p < t.point_count(); p += step) {
    const int found = t.find(t.labels[p]);
    if (found < 0 || found > p || t.labels[found] != t.labels[p]) std::abort();
  }
  if (t.frame_count() > 0 && t.point_count() > 0) {
    const int last_frame = t.frame_count() - 1;
    const int last_point = t.point_count() - 1;
    if (t.position(last_frame, last_point) != t.positions.back()) std::abort();
    if (t.is_present(last_frame, last_point) != (t.present.back() == 1)) std::abort();
  }
  const double missing = t.missing_fraction();
  if (!(missing >= 0 && missing <= 1)) std::abort();
  return 0;
}
