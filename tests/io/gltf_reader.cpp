#include "tests/io/gltf_reader.hpp"

#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>

#include "io/read_file.hpp"
#include "tests/fixtures/fixtures.hpp"

namespace gltf_test {

namespace {

std::vector<std::uint8_t> base64_decode(const std::string& s, bool& ok) {
  auto value = [](char c) -> int {
    if (c >= 'A' && c <= 'Z') return c - 'A';
    if (c >= 'a' && c <= 'z') return c - 'a' + 26;
    if (c >= '0' && c <= '9') return c - '0' + 52;
    if (c == '+') return 62;
    if (c == '/') return 63;
    return -1;
  };
  std::vector<std::uint8_t> out;
  ok = s.size() % 4 == 0;
  std::uint32_t acc = 0;
  int bits = 0;
  size_t pad = 0;
  for (size_t i = 0; i < s.size() && ok; ++i) {
    if (s[i] == '=') {
      ++pad;
      continue;
    }
    const int v = value(s[i]);
    if (v < 0 || pad > 0) {
      ok = false;
      break;
    }
    acc = (acc << 6) | static_cast<std::uint32_t>(v);
    bits += 6;
    if (bits >= 8) {
      bits -= 8;
      out.push_back(static_cast<std::uint8_t>((acc >> bits) & 0xff));
    }
  }
  ok = ok && pad <= 2;
  return out;
}

std::uint32_t u32_at(const std::vector<std::uint8_t>& b, size_t at) {
  return static_cast<std::uint32_t>(b[at]) | (static_cast<std::uint32_t>(b[at + 1]) << 8) |
         (static_cast<std::uint32_t>(b[at + 2]) << 16) |
         (static_cast<std::uint32_t>(b[at + 3]) << 24);
}

size_t component_size(int type) {
  switch (type) {
    case 5120:
    case 5121:
      return 1;
    case 5122:
    case 5123:
      return 2;
    case 5125:
    case 5126:
      return 4;
  }
  return 0;
}

double component_at(const std::uint8_t* p, int type) {
  switch (type) {
    case 5121:
      return *p;
    case 5123: {
      std::uint16_t v;
      std::memcpy(&v, p, 2);
      return v;
    }
    case 5125: {
      std::uint32_t v;
      std::memcpy(&v, p, 4);
      return v;
    }
    case 5126: {
      float v;
      std::memcpy(&v, p, 4);
      return v;
    }
  }
  return 0;
}

Eigen::Matrix4d trs(const Eigen::Vector3d& t,
                    const Eigen::Quaterniond& r,
                    const Eigen::Vector3d& s) {
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m.topLeftCorner<3, 3>() = r.toRotationMatrix() * s.asDiagonal();
  m.topRightCorner<3, 1>() = t;
  return m;
}

// a node's static translation, rotation and scale (identity defaults)
struct NodeTrs {
  Eigen::Vector3d t = Eigen::Vector3d::Zero();
  Eigen::Quaterniond r = Eigen::Quaterniond::Identity();
  Eigen::Vector3d s = Eigen::Vector3d::Ones();
};
NodeTrs node_trs(const Json& node) {
  NodeTrs x;
  if (node.contains("translation")) {
    for (int k = 0; k < 3; ++k) x.t[k] = node["translation"][k];
  }
  if (node.contains("rotation")) {
    const Json& q = node["rotation"];
    x.r = Eigen::Quaterniond(q[3].get<double>(), q[0].get<double>(), q[1].get<double>(),
                             q[2].get<double>());
  }
  if (node.contains("scale")) {
    for (int k = 0; k < 3; ++k) x.s[k] = node["scale"][k];
  }
  return x;
}

}  // namespace

int components(const std::string& type) {
  if (type == "SCALAR") return 1;
  if (type == "VEC2") return 2;
  if (type == "VEC3") return 3;
  if (type == "VEC4") return 4;
  if (type == "MAT4") return 16;
  return 0;
}

Document parse_gltf(const std::string& text, std::vector<std::string>& errors) {
  Document doc;
  doc.json = Json::parse(text);
  const std::string uri = doc.json.at("buffers").at(0).at("uri");
  const std::string prefix = "data:application/octet-stream;base64,";
  if (uri.rfind(prefix, 0) != 0) {
    errors.push_back("buffer 0 is not a base64 data URI");
    return doc;
  }
  bool ok = false;
  doc.bin = base64_decode(uri.substr(prefix.size()), ok);
  if (!ok) errors.push_back("buffer 0: malformed base64");
  return doc;
}

Document parse_glb(const std::vector<std::uint8_t>& b, std::vector<std::string>& errors) {
  Document doc;
  if (b.size() < 28) {
    errors.push_back("GLB shorter than a header and two chunk headers");
    return doc;
  }
  if (u32_at(b, 0) != 0x46546C67) errors.push_back("GLB magic is not 'glTF'");
  if (u32_at(b, 4) != 2) errors.push_back("GLB version is not 2");
  if (u32_at(b, 8) != b.size()) errors.push_back("GLB length field differs from the file size");
  if (b.size() % 4 != 0) errors.push_back("GLB length is not a multiple of 4");
  const size_t json_len = u32_at(b, 12);
  if (u32_at(b, 16) != 0x4E4F534A) errors.push_back("first chunk is not JSON");
  if (json_len % 4 != 0) errors.push_back("JSON chunk length is not a multiple of 4");
  if (20 + json_len + 8 > b.size()) {
    errors.push_back("JSON chunk runs past the end");
    return doc;
  }
  const std::string json(b.begin() + 20, b.begin() + 20 + json_len);
  doc.json = Json::parse(json);
  const size_t at = 20 + json_len;
  const size_t bin_len = u32_at(b, at);
  if (u32_at(b, at + 4) != 0x004E4942) errors.push_back("second chunk is not BIN");
  if (bin_len % 4 != 0) errors.push_back("BIN chunk length is not a multiple of 4");
  if (at + 8 + bin_len != b.size()) errors.push_back("BIN chunk does not end the file");
  if (at + 8 + bin_len > b.size()) return doc;
  doc.bin.assign(b.begin() + at + 8, b.begin() + at + 8 + bin_len);
  // the buffer may be up to 3 bytes shorter than the padded chunk
  const size_t declared = doc.json.at("buffers").at(0).at("byteLength");
  if (declared > bin_len || bin_len - declared > 3) {
    errors.push_back("buffer byteLength " + std::to_string(declared) + " does not fit BIN chunk " +
                     std::to_string(bin_len));
  }
  if (declared <= doc.bin.size()) doc.bin.resize(declared);
  return doc;
}

Document load(const std::string& path, std::vector<std::string>& errors) {
  const std::vector<std::uint8_t> bytes = read_bytes(path);
  if (path.size() >= 4 && path.substr(path.size() - 4) == ".glb") return parse_glb(bytes, errors);
  return parse_gltf(std::string(bytes.begin(), bytes.end()), errors);
}

void check_layout(const Document& doc, std::vector<std::string>& errors) {
  const Json& j = doc.json;
  const size_t byte_length = j.at("buffers").at(0).at("byteLength");
  if (byte_length != doc.bin.size()) {
    errors.push_back("buffer byteLength " + std::to_string(byte_length) + " != data size " +
                     std::to_string(doc.bin.size()));
  }
  const Json& views = j.at("bufferViews");
  for (size_t v = 0; v < views.size(); ++v) {
    const size_t off = views[v].value("byteOffset", size_t{0});
    const size_t len = views[v].at("byteLength");
    if (off % 4 != 0) errors.push_back("bufferView " + std::to_string(v) + " not 4-byte aligned");
    if (off + len > byte_length) errors.push_back("bufferView " + std::to_string(v) + " too long");
    if (views[v].contains("byteStride")) {
      errors.push_back("bufferView " + std::to_string(v) + " has a byteStride");
    }
  }
  const Json& acc = j.at("accessors");
  for (size_t a = 0; a < acc.size(); ++a) {
    const std::string at = "accessor " + std::to_string(a) + ": ";
    const Json& x = acc[a];
    const size_t view = x.at("bufferView");
    const size_t elem =
        component_size(x.at("componentType")) * components(x.at("type").get<std::string>());
    const size_t need = x.value("byteOffset", size_t{0}) + elem * x.at("count").get<size_t>();
    if (need > views.at(view).at("byteLength").get<size_t>()) {
      errors.push_back(at + "runs past its buffer view");
      continue;
    }
    if (!x.contains("min") && !x.contains("max")) continue;
    const std::vector<double> values = read_accessor(doc, static_cast<int>(a));
    const int nc = components(x.at("type").get<std::string>());
    for (int c = 0; c < nc; ++c) {
      double lo = std::numeric_limits<double>::infinity(), hi = -lo;
      for (size_t k = c; k < values.size(); k += nc) {
        lo = std::min(lo, values[k]);
        hi = std::max(hi, values[k]);
      }
      if (x.at("min").at(c).get<double>() != lo) errors.push_back(at + "min differs from the data");
      if (x.at("max").at(c).get<double>() != hi) errors.push_back(at + "max differs from the data");
    }
  }
  // POSITION and animation inputs must declare bounds
  if (j.contains("meshes")) {
    for (const Json& m : j["meshes"]) {
      for (const Json& p : m.at("primitives")) {
        const Json& a = acc.at(p.at("attributes").at("POSITION").get<size_t>());
        if (!a.contains("min") || !a.contains("max")) errors.push_back("POSITION without bounds");
      }
    }
  }
  if (j.contains("animations")) {
    for (const Json& an : j["animations"]) {
      for (const Json& s : an.at("samplers")) {
        const Json& a = acc.at(s.at("input").get<size_t>());
        if (!a.contains("min") || !a.contains("max"))
          errors.push_back("animation input without bounds");
      }
    }
  }
}

std::vector<double> read_accessor(const Document& doc, int a) {
  const Json& x = doc.json.at("accessors").at(a);
  const Json& v = doc.json.at("bufferViews").at(x.at("bufferView").get<size_t>());
  const int type = x.at("componentType");
  const size_t nc = components(x.at("type").get<std::string>());
  const size_t count = x.at("count");
  const size_t cs = component_size(type);
  const size_t base = v.value("byteOffset", size_t{0}) + x.value("byteOffset", size_t{0});
  if (base + count * nc * cs > doc.bin.size()) throw std::runtime_error("accessor out of buffer");
  std::vector<double> out(count * nc);
  for (size_t k = 0; k < count * nc; ++k)
    out[k] = component_at(doc.bin.data() + base + k * cs, type);
  return out;
}

Eigen::Matrix4d static_local(const Json& node) {
  if (node.contains("matrix")) {
    Eigen::Matrix4d m;
    for (int k = 0; k < 16; ++k) m(k % 4, k / 4) = node["matrix"][k].get<double>();
    return m;
  }
  const NodeTrs x = node_trs(node);
  return trs(x.t, x.r, x.s);
}

std::vector<std::vector<Eigen::Matrix4d>> world_matrices_at_keys(const Document& doc, int a) {
  const Json& nodes = doc.json.at("nodes");
  const size_t n = nodes.size();
  std::vector<int> parent(n, -1);
  for (size_t i = 0; i < n; ++i) {
    if (!nodes[i].contains("children")) continue;
    for (const Json& c : nodes[i]["children"]) parent[c.get<size_t>()] = static_cast<int>(i);
  }
  // static T, R, S per node
  std::vector<Eigen::Vector3d> T(n), S(n);
  std::vector<Eigen::Quaterniond> R(n);
  for (size_t i = 0; i < n; ++i) {
    const NodeTrs x = node_trs(nodes[i]);
    T[i] = x.t;
    R[i] = x.r;
    S[i] = x.s;
  }
  size_t nkeys = 1;
  struct Channel {
    int node;
    std::string path;
    std::vector<double> values;
  };
  std::vector<Channel> channels;
  if (doc.json.contains("animations") && a < static_cast<int>(doc.json["animations"].size())) {
    const Json& an = doc.json["animations"][a];
    const std::vector<double> times =
        read_accessor(doc, an.at("samplers").at(0).at("input").get<int>());
    nkeys = times.size();
    for (const Json& ch : an.at("channels")) {
      const Json& s = an.at("samplers").at(ch.at("sampler").get<size_t>());
      channels.push_back({ch.at("target").at("node").get<int>(), ch.at("target").at("path"),
                          read_accessor(doc, s.at("output").get<int>())});
    }
  }
  std::vector<std::vector<Eigen::Matrix4d>> out(nkeys, std::vector<Eigen::Matrix4d>(n));
  for (size_t k = 0; k < nkeys; ++k) {
    std::vector<Eigen::Vector3d> t = T, s = S;
    std::vector<Eigen::Quaterniond> r = R;
    for (const Channel& c : channels) {
      const double* v = c.values.data();
      if (c.path == "translation")
        t[c.node] = Eigen::Vector3d(v[3 * k], v[3 * k + 1], v[3 * k + 2]);
      if (c.path == "scale") s[c.node] = Eigen::Vector3d(v[3 * k], v[3 * k + 1], v[3 * k + 2]);
      if (c.path == "rotation") {
        r[c.node] = Eigen::Quaterniond(v[4 * k + 3], v[4 * k], v[4 * k + 1], v[4 * k + 2]);
      }
    }
    // parents before children is not guaranteed by glTF: resolve each node by walking up
    std::vector<char> done(n, 0);
    for (size_t i = 0; i < n; ++i) {
      std::vector<int> chain;
      for (int j = static_cast<int>(i); j >= 0 && !done[j]; j = parent[j]) chain.push_back(j);
      for (auto it = chain.rbegin(); it != chain.rend(); ++it) {
        const int j = *it;
        const Eigen::Matrix4d local =
            nodes[j].contains("matrix") ? static_local(nodes[j]) : trs(t[j], r[j], s[j]);
        out[k][j] = parent[j] >= 0 ? Eigen::Matrix4d(out[k][parent[j]] * local) : local;
        done[j] = 1;
      }
    }
  }
  return out;
}

CommandResult run(const std::string& command, bool merge_stderr) {
  CommandResult r;
  const std::string cmd = command + (merge_stderr ? " 2>&1" : "");
  FILE* p = ::popen(cmd.c_str(), "r");
  if (p == nullptr) return r;
  char buf[65536];
  size_t n;
  while ((n = std::fread(buf, 1, sizeof buf, p)) > 0) r.out.append(buf, n);
  const int st = ::pclose(p);
  r.status = (st != -1 && WIFEXITED(st)) ? WEXITSTATUS(st) : -1;
  return r;
}

std::string quote(const std::string& s) {
  std::string out = "'";
  for (char c : s) {
    if (c == '\'')
      out += "'\\''";
    else
      out += c;
  }
  return out + "'";
}

std::string node_modules() { return fixtures::source_dir() + "/web/node_modules"; }
std::string script(const std::string& name) { return fixtures::source_dir() + "/tests/io/" + name; }

std::string node_unavailable() {
  if (run("command -v node >/dev/null 2>&1").status != 0) return "`node` is not on PATH";
  namespace fs = std::filesystem;
  for (const char* pkg : {"three", "gltf-validator"}) {
    if (!fs::exists(node_modules() + "/" + pkg + "/package.json")) {
      return node_modules() + "/" + pkg + " is missing (run `npm ci` in web/)";
    }
  }
  return {};
}

Json validate(const std::string& file) {
  const CommandResult r = run("node " + quote(script("gltf_validate.mjs")) + " " +
                              quote(node_modules()) + " " + quote(file));
  if (r.status != 0) throw std::runtime_error("gltf_validate.mjs failed on " + file);
  return Json::parse(r.out);
}

Json three_read(const std::string& file, const std::string& mode_args) {
  const CommandResult r = run("node " + quote(script("gltf_three_reader.mjs")) + " " +
                              quote(node_modules()) + " " + quote(file) + " " + mode_args);
  if (r.status != 0) throw std::runtime_error("gltf_three_reader.mjs failed on " + file);
  return Json::parse(r.out);
}

TempDir::TempDir() {
  std::string tmpl = (std::filesystem::temp_directory_path() / "pindrag-gltf-XXXXXX").string();
  if (::mkdtemp(tmpl.data()) == nullptr) throw std::runtime_error("mkdtemp failed");
  dir_ = tmpl;
}
TempDir::~TempDir() {
  std::error_code ec;
  std::filesystem::remove_all(dir_, ec);
}

std::vector<std::uint8_t> read_bytes(const std::string& path) {
  const std::string bytes = io::read_file(path, std::size_t{1} << 30, "a file a test reads");
  return std::vector<std::uint8_t>(bytes.begin(), bytes.end());
}

void write_bytes(const std::string& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

}  // namespace gltf_test
