// libFuzzer harness for io/character_json.hpp. Any input must either load or fail with
// core::ModelError; nothing else may escape, crash, hang or leak. A model that loads must
// round-trip exactly: load(write(m)) == m and write(load(write(m))) == write(m).
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "io/character_json.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  io::LoadResult first;
  try {
    first = io::load_character_json_string(text, "fuzz.json", "");
  } catch (const core::ModelError&) {
    return 0;
  }
  const std::string written = io::write_character_json(*first.model);
  const io::LoadResult second = io::load_character_json_string(written, "fuzz-rewritten.json", "");
  if (!(*second.model == *first.model)) std::abort();
  if (io::write_character_json(*second.model) != written) std::abort();
  return 0;
}
