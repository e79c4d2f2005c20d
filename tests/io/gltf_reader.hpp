// A minimal glTF 2.0 reader for the tests (nlohmann-json), written against the specification and
// independent of io/gltf.cpp and of tinygltf, which serializes its documents: it parses .gltf
// (data-URI buffer) and .glb, checks the container and buffer layout, reads accessors and
// evaluates node world matrices at animation keys. Also: running the Node.js helpers (three.js,
// Khronos validator) and assimp's CLI.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace gltf_test {

using Json = nlohmann::json;

struct Document {
  Json json;
  std::vector<std::uint8_t> bin;  // buffer 0
};

/// Parses .gltf text whose buffer 0 is a base64 data URI. Problems are added to `errors`.
Document parse_gltf(const std::string& text, std::vector<std::string>& errors);
/// Parses a GLB, checking the header, chunk order, chunk lengths and 4-byte padding.
Document parse_glb(const std::vector<std::uint8_t>& bytes, std::vector<std::string>& errors);

/// Parses a .gltf or .glb file by its extension.
Document load(const std::string& path, std::vector<std::string>& errors);

/// Checks buffer views (4-byte aligned, inside the buffer), buffer byteLength == data size,
/// accessors inside their views without byteStride, and that every declared min/max equals the
/// data exactly, and that POSITION and animation inputs have bounds.
void check_layout(const Document& doc, std::vector<std::string>& errors);

/// Accessor values as doubles (float, unsigned short/int, unsigned byte components).
std::vector<double> read_accessor(const Document& doc, int accessor);
/// Components per element: SCALAR 1, VEC3 3, VEC4 4, MAT4 16.
int components(const std::string& type);

/// Local matrix T·R·S of node n from its static properties (identity defaults).
Eigen::Matrix4d static_local(const Json& node);

/// World matrices of every node at every key of animation `a` (input of its first sampler),
/// applying the channel values at that key (LINEAR keys are sampled exactly at their times).
/// Without animations, one frame of static world matrices.
std::vector<std::vector<Eigen::Matrix4d>> world_matrices_at_keys(const Document& doc, int a);

/// Result of running a command.
struct CommandResult {
  int status = -1;  // exit status, or -1 when it did not exit normally
  std::string out;  // standard output
};
/// Runs a shell command (stderr joins stdout only when `merge_stderr`).
CommandResult run(const std::string& command, bool merge_stderr = false);
/// Shell-quoted argument.
std::string quote(const std::string& s);

/// Why Node.js checks cannot run ("" when `node` is on PATH and web/node_modules has three and
/// gltf-validator).
std::string node_unavailable();
/// web/node_modules of the source tree.
std::string node_modules();
/// tests/io/<name> in the source tree.
std::string script(const std::string& name);

/// Runs gltf_validate.mjs on one file; the parsed JSON report.
Json validate(const std::string& file);
/// Runs gltf_three_reader.mjs with the given mode arguments; the parsed JSON.
Json three_read(const std::string& file, const std::string& mode_args);

/// A fresh folder under the system temporary folder, removed by the destructor.
class TempDir {
 public:
  TempDir();
  ~TempDir();
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  std::string path(const std::string& name) const { return dir_ + "/" + name; }
  const std::string& dir() const { return dir_; }

 private:
  std::string dir_;
};

/// The bytes of a file (at most 1 GiB). @throws io::FileError naming the file
std::vector<std::uint8_t> read_bytes(const std::string& path);
void write_bytes(const std::string& path, const std::string& bytes);

}  // namespace gltf_test
