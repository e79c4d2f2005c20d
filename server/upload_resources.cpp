#include "server/upload_resources.hpp"

#include <algorithm>
#include <cctype>
#include <map>
#include <nlohmann/json.hpp>

#include "server/security.hpp"
#include "server/uploads.hpp"

namespace server {

namespace {

// the name is a file in the upload's own folder and nothing else
bool plain_file_name(const std::string& name) {
  if (name.empty() || name.size() > 255 || name.front() == '.') return false;
  return std::none_of(name.begin(), name.end(), [](unsigned char c) {
    return c < 0x20 || c == 0x7f || c == '/' || c == '\\';
  });
}

// RFC 3986 percent-decoding of a relative URI ("my%20skin.bin" names "my skin.bin")
std::string percent_decoded(const std::string& uri) {
  std::string out;
  for (std::size_t i = 0; i < uri.size(); ++i) {
    if (uri[i] == '%' && i + 2 < uri.size() &&
        std::isxdigit(static_cast<unsigned char>(uri[i + 1])) &&
        std::isxdigit(static_cast<unsigned char>(uri[i + 2]))) {
      out += static_cast<char>(std::stoi(uri.substr(i + 1, 2), nullptr, 16));
      i += 2;
    } else {
      out += uri[i];
    }
  }
  return out;
}

// The "uri" strings of the top-level "buffers" array's objects, read with nlohmann's SAX
// interface: a 64 MiB .gltf of numbers would take several times its size as a DOM in the
// server's own process (the import itself runs in a limited child).
class BufferUris final : public nlohmann::json_sax<nlohmann::json> {
 public:
  std::vector<std::string> uris;

  bool start_object(std::size_t) override { return open(); }
  bool end_object() override { return close(); }
  bool start_array(std::size_t) override {
    in_buffers_ = depth_ == 1 && top_key_ == "buffers";
    return open();
  }
  bool end_array() override {
    if (depth_ == 2) in_buffers_ = false;
    return close();
  }
  bool key(string_t& k) override {
    if (depth_ == 1) top_key_ = k;
    uri_next_ = in_buffers_ && depth_ == 3 && k == "uri";
    return true;
  }
  bool string(string_t& v) override {
    if (uri_next_) uris.push_back(v);
    return value();
  }
  bool null() override { return value(); }
  bool boolean(bool) override { return value(); }
  bool number_integer(number_integer_t) override { return value(); }
  bool number_unsigned(number_unsigned_t) override { return value(); }
  bool number_float(number_float_t, const string_t&) override { return value(); }
  bool binary(binary_t&) override { return value(); }
  bool parse_error(std::size_t, const std::string&, const nlohmann::detail::exception&) override {
    return false;
  }

 private:
  bool open() {
    ++depth_;
    uri_next_ = false;
    return true;
  }
  bool close() {
    --depth_;
    return true;
  }
  bool value() {
    uri_next_ = false;
    return true;
  }
  int depth_ = 0;            // containers open around the next event
  std::string top_key_;      // the last key of the top-level object
  bool in_buffers_ = false;  // inside the top-level "buffers" array
  bool uri_next_ = false;    // the next value is a buffer's "uri"
};

// glTF 2.0 §3.3.2 (buffers): a buffer without a URI is the GLB's own chunk; a data: URI is
// embedded; any other URI names a file relative to the .gltf. Text that is not JSON is left to
// the importer, which names what is wrong with it.
struct BufferFile {
  std::string uri;   // as the .gltf writes it
  std::string name;  // the file it names (percent-decoded)
};
std::vector<BufferFile> referenced_buffer_files(const std::string& gltf_text) {
  BufferUris reader;
  if (!nlohmann::json::sax_parse(gltf_text, &reader)) return {};
  std::vector<BufferFile> files;
  for (const std::string& uri : reader.uris) {
    if (uri.rfind("data:", 0) == 0) continue;
    files.push_back({uri, percent_decoded(uri)});
  }
  return files;
}

}  // namespace

std::vector<StoredResource> check_upload_resources(const std::string& field,
                                                   const std::string& shown,
                                                   const std::string& ext,
                                                   const std::string& bytes,
                                                   const std::vector<UploadResource>& resources,
                                                   const UploadCaps& caps) {
  if (!resources.empty() && ext != ".gltf" && ext != ".glb" && ext != ".fbx" && ext != ".dae") {
    throw UploadError(400, "resource: \"" + shown + "\" references no other files (rule: only a " +
                               ".gltf, .glb, .fbx or .dae is sent with the files it references, "
                               "its buffers and images)");
  }
  if (resources.size() > static_cast<std::size_t>(kMaxUploadResources)) {
    throw UploadError(400, "resource: " + std::to_string(resources.size()) + " files sent with \"" +
                               shown + "\" (rule: at most " + std::to_string(kMaxUploadResources) +
                               ")");
  }
  std::map<std::string, const UploadResource*> by_name;
  std::size_t total = bytes.size();
  for (const UploadResource& r : resources) {
    const std::string name = safe_file_name(r.name, "?");
    if (!plain_file_name(r.name) || lower(r.name) == "upload" + ext) {
      throw UploadError(400, "resource: \"" + name +
                                 "\" is not a plain file name (rule: a name in the file's own "
                                 "folder: no folder, not hidden, no control characters, not "
                                 "upload" +
                                 ext + ", the name the upload is stored under)");
    }
    if (!by_name.emplace(r.name, &r).second) {
      throw UploadError(400, "resource: \"" + name + "\" is sent twice");
    }
    total += r.bytes.size();
  }
  const UploadCap cap = upload_cap(caps, ext);
  if (!resources.empty() && total > cap.bytes) {
    throw UploadError(
        413, field + ": \"" + shown + "\" and its " + std::to_string(resources.size()) +
                 " resource files are " + byte_text(total) + ", over the upload cap of " +
                 byte_text(cap.bytes) + " for " + ext + " files (set by " + cap.setting + ")");
  }
  std::vector<StoredResource> stored;
  for (const UploadResource& r : resources) stored.push_back({r.name, &r});
  if (ext != ".gltf") return stored;
  for (const BufferFile& buffer : referenced_buffer_files(bytes)) {
    const std::string& uri = buffer.uri;
    const std::string& file = buffer.name;
    if (const auto sent = by_name.find(file); sent != by_name.end()) {
      // assimp opens the URI's text as it stands: an encoded name is stored under it as well
      if (uri != file && plain_file_name(uri) && by_name.emplace(uri, sent->second).second) {
        stored.push_back({uri, sent->second});
      }
      continue;
    }
    const std::string why =
        file.find('/') != std::string::npos || file.find('\\') != std::string::npos
            ? " in another folder"
            : ", which was not sent with it";
    throw UploadError(422, field + ": \"" + shown + "\" references the buffer \"" +
                               safe_file_name(file, "?") + "\"" + why +
                               " (rule: a .gltf comes with the files its buffers name, beside it: "
                               "choose them together in the page, or upload the .glb)");
  }
  return stored;
}

}  // namespace server
