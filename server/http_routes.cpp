#include "server/http_routes.hpp"

#include <cerrno>
#include <filesystem>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>
#include <system_error>

#include "animator/document_json.hpp"
#include "animator/session_file.hpp"
#include "io/bundled_characters.hpp"
#include "io/bvh.hpp"
#include "io/gltf.hpp"
#include "io/json_parse.hpp"
#include "server/mesh_binary.hpp"
#include "server/protocol.hpp"
#include "server/uploads.hpp"
#if PINDRAG_HAVE_THUMBNAIL
#include "server/thumbnail.hpp"
#endif

namespace server {
namespace {

using nlohmann::json;
namespace fs = std::filesystem;

constexpr const char* kVersion = "0.1.0";
constexpr const char* kTokenHeader = "X-Session-Token";
constexpr const char* kServerKeyHeader = "X-Server-Key";
constexpr const char* kRetryAfterSeconds = "2";

void send_json(httplib::Response& res, int status, const json& body) {
  res.status = status;
  res.set_content(body.dump(-1, ' ', false, json::error_handler_t::replace), "application/json");
}

// The multipart field "mapping" of a retargeting upload: a mapping document (docs/retargeting.md,
// "Mapping file"). @throws UploadError 422 naming the field and the rule
std::vector<animator::MappingEntry> mapping_field(const httplib::MultipartFormData& field) {
  try {
    return animator::mapping_from_json(
        io::parse_json(field.content, "mapping", io::JsonLimits{.max_bytes = std::size_t{1} << 20}),
        "mapping");
  } catch (const std::exception& e) {
    throw UploadError(422, e.what());
  }
}

void send_error(httplib::Response& res, int status, const std::string& message) {
  send_json(res, status, json{{"error", message}});
}

// the files sent beside an uploaded file (form fields "resource"), for a .gltf's buffers and images
std::vector<UploadResource> resource_fields(const httplib::Request& req) {
  std::vector<UploadResource> resources;
  const auto [first, last] = req.files.equal_range("resource");
  for (auto it = first; it != last; ++it) {
    resources.push_back({it->second.filename, it->second.content});
  }
  return resources;
}

// Whether the request is a multipart form with a file field "clip"; else a 400 is sent.
bool has_clip_file(const httplib::Request& req, httplib::Response& res) {
  if (req.is_multipart_form_data() && req.has_file("clip")) return true;
  send_error(res, 400, "clip: a multipart file field \"clip\" is required");
  return false;
}

std::string content_type(const fs::path& path) {
  const std::string ext = path.extension().string();
  if (ext == ".html") return "text/html; charset=utf-8";
  if (ext == ".js" || ext == ".mjs") return "text/javascript; charset=utf-8";
  if (ext == ".css") return "text/css; charset=utf-8";
  if (ext == ".json" || ext == ".map") return "application/json";
  if (ext == ".png") return "image/png";
  if (ext == ".jpg" || ext == ".jpeg") return "image/jpeg";
  if (ext == ".svg") return "image/svg+xml";
  if (ext == ".ico") return "image/x-icon";
  if (ext == ".wasm") return "application/wasm";
  if (ext == ".txt" || ext == ".md") return "text/plain; charset=utf-8";
  return "application/octet-stream";
}

// A body sent with its length known up front. cpp-httplib compresses set_content() bodies of text
// types whenever the client accepts it, and Debian's build picks Brotli at its slowest quality:
// three.js (1.5 MB) then takes over ten seconds to serve. Loopback needs no compression.
void set_uncompressed(httplib::Response& res, std::string body, const std::string& type) {
  auto shared = std::make_shared<const std::string>(std::move(body));
  res.set_content_provider(shared->size(), type,
                           [shared](size_t offset, size_t length, httplib::DataSink& sink) {
                             return sink.write(shared->data() + offset, length);
                           });
}

void send_file(httplib::Response& res, const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream bytes;
  bytes << in.rdbuf();
  if (!in) {
    send_error(res, 404, "path: the file cannot be read");
    return;
  }
  res.set_header("Cache-Control", "no-cache");
  res.set_header("X-Content-Type-Options", "nosniff");
  set_uncompressed(res, bytes.str(), content_type(path));
}

// Creating and listing sessions on a server reachable from other machines needs its key.
bool server_key_ok(const RouteContext& ctx, const httplib::Request& req, httplib::Response& res) {
  if (ctx.server_key.empty() ||
      tokens_equal(req.get_header_value(kServerKeyHeader), ctx.server_key))
    return true;
  send_error(res, 401,
             std::string(kServerKeyHeader) +
                 ": missing or wrong server key (rule: a server listening beyond loopback needs "
                 "the key it printed, ?key= in its URL)");
  return false;
}

// largest frame index a request may name (thumbnail, export range)
constexpr int kMaxFrameParam = 1'000'000'000;

// the limits a client may want to know before it sends something (docs/protocol.md, "Limits")
json limits_json(const UploadRules& r, std::size_t live_sessions) {
  const UploadCaps& c = r.caps;
  const animator::Limits& l = r.limits;
  return {{"upload_bytes", c.largest()},
          {"upload_bytes_by_type",
           {{"urdf", c.urdf},
            {"json", c.json},
            {"bvh", c.bvh},
            {"gltf", c.gltf},
            {"fbx", c.fbx},
            {"dae", c.dae},
            {"c3d", c.c3d}}},
          {"ws_message_bytes", kMaxWsMessageBytes},
          {"clip_seconds", l.max_clip_seconds},
          {"clip_frames", l.max_clip_frames},
          {"clip_values", l.max_clip_values},
          {"keys", l.max_keys},
          {"layers", l.max_layers},
          {"undo_bytes", l.max_undo_bytes},
          {"live_sessions", live_sessions}};
}

bool is_state_changing(const std::string& method) {
  return method == "POST" || method == "PUT" || method == "DELETE" || method == "PATCH";
}

// The session named in the path, checked against the token header; answers 401/404 itself.
std::shared_ptr<SessionActor> session_of(const RouteContext& ctx,
                                         const httplib::Request& req,
                                         httplib::Response& res) {
  const std::string id = req.matches[1];
  if (!is_valid_id(id)) {
    send_error(res, 404, "id: no such session (rule: 32 lowercase hex digits)");
    return nullptr;
  }
  const SessionLookup found = ctx.registry->find(id, req.get_header_value(kTokenHeader));
  if (found.status == 404) send_error(res, 404, "id: no such session");
  if (found.status == 401)
    send_error(res, 401, std::string(kTokenHeader) + ": missing or wrong session token");
  return found.actor;
}

std::optional<int> int_param(
    const httplib::Request& req, const char* name, httplib::Response& res, int lo, int hi) {
  if (!req.has_param(name)) return std::nullopt;
  const std::string text = req.get_param_value(name);
  int value = 0;
  size_t used = 0;
  try {
    value = std::stoi(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != text.size() || value < lo || value > hi) {
    send_error(res, 400,
               std::string(name) + ": must be an integer in [" + std::to_string(lo) + ", " +
                   std::to_string(hi) + "]");
    throw std::invalid_argument(name);
  }
  return value;
}

// `units` (m, cm, source) and `order` (XYZ, ..., ZYX, source) of a BVH export; source, the
// default, is the character's BVH file when it came from one (io/bvh_writer.hpp). A bad value
// or one given with another format is a 400 naming the parameter (and throws).
io::BvhExportOptions bvh_params(const httplib::Request& req,
                                const std::string& format,
                                httplib::Response& res) {
  io::BvhExportOptions o;
  try {
    const bool units = req.has_param("units"), order = req.has_param("order");
    if ((units || order) && format != "bvh") {
      throw std::invalid_argument(std::string(units ? "units" : "order") + ": needs format=bvh");
    }
    if (units) o.scale = io::parse_bvh_units(req.get_param_value("units"), "units");
    if (order) o.rotation_order = io::parse_bvh_order(req.get_param_value("order"), "order");
  } catch (const std::invalid_argument& e) {
    send_error(res, 400, e.what());
    throw;
  }
  return o;
}

// The saved sessions: the list (no tokens) and deleting one with its token.
void register_session_list(httplib::Server& http, const RouteContext& ctx) {
  http.Get("/api/sessions", [&ctx](const httplib::Request& req, httplib::Response& res) {
    if (!server_key_ok(ctx, req, res)) return;
    json list = json::array();
    for (const SessionInfo& s : ctx.registry->list()) {
      list.push_back({{"id", s.id},
                      {"character", s.character},
                      {"modified", s.modified},
                      {"bytes", s.bytes},
                      {"live", s.live}});
    }
    send_json(res, 200, list);
  });
  http.Delete(R"(/api/sessions/([^/]+))", [&ctx](const httplib::Request& req,
                                                 httplib::Response& res) {
    const std::string id = req.matches[1];
    if (!is_valid_id(id))
      return send_error(res, 404, "id: no such session (rule: 32 lowercase hex digits)");
    switch (ctx.registry->remove(id, req.get_header_value(kTokenHeader))) {
      case 200:
        return send_json(res, 200, {{"deleted", id}});
      case 401:
        return send_error(res, 401, std::string(kTokenHeader) + ": missing or wrong session token");
      case 409:
        return send_error(res, 409,
                          "id: the session is open in a page or a request; close it first");
      default:
        return send_error(res, 404, "id: no such session");
    }
  });
}

void register_static(httplib::Server& http, const RouteContext& ctx) {
  const fs::path web_root = ctx.web_root;
  http.Get("/", [web_root](const httplib::Request&, httplib::Response& res) {
    std::string why;
    const auto index = resolve_static_path(web_root, "/index.html", {}, &why);
    if (!index) return send_error(res, 404, "index.html: " + why);
    send_file(res, *index);
  });
  http.Get(
      R"(/vendor/three/(.*))", [web_root](const httplib::Request& req, httplib::Response& res) {
        const std::string rest = req.matches[1];
        if (rest.rfind("build/", 0) != 0 && rest.rfind("examples/jsm/", 0) != 0) {
          return send_error(res, 404, "path: /vendor/three/ serves build/ and examples/jsm/ only");
        }
        std::string why;
        const auto file = resolve_static_path(web_root / "node_modules" / "three", rest, {}, &why);
        if (!file) return send_error(res, 404, "path: " + why);
        send_file(res, *file);
      });
  http.Get(R"(/(.+))", [web_root](const httplib::Request& req, httplib::Response& res) {
    if (req.path.rfind("/api/", 0) == 0) return send_error(res, 404, "path: no such API route");
    std::string why;
    const auto file = resolve_static_path(web_root, req.path, {"node_modules"}, &why);
    if (!file) return send_error(res, 404, "path: " + why);
    send_file(res, *file);
  });
}

void register_api(httplib::Server& http, const RouteContext& ctx) {
  http.Get("/api/health", [](const httplib::Request&, httplib::Response& res) {
    send_json(res, 200, {{"status", "ok"}, {"version", kVersion}});
  });
  http.Get("/api/config", [&ctx](const httplib::Request& req, httplib::Response& res) {
    // the WebSocket URL on the name the page was loaded from (the Host check admitted it)
    std::string host = HostPolicy::host_name(req.get_header_value("Host"));
    if (host.empty()) host = "127.0.0.1";
    send_json(res, 200,
              {{"protocol", kProtocolVersion},
               {"ws_url", "ws://" + host + ":" + std::to_string(ctx.policy->ws_port()) + "/ws"},
               {"create_needs_key", !ctx.server_key.empty()},
               {"limits", limits_json(ctx.uploads, ctx.registry->options().max_live)}});
  });
  http.Get("/api/characters", [&ctx](const httplib::Request&, httplib::Response& res) {
    json list = json::array();
    for (const auto& c : io::bundled_characters())
      list.push_back({{"name", c.name}, {"description", c.description}});
    if (!ctx.served_character_name.empty()) {
      list.push_back({{"name", ctx.served_character_name},
                      {"description", "the character this server was started with"}});
    }
    send_json(res, 200, list);
  });
  http.Post("/api/sessions", [&ctx](const httplib::Request& req, httplib::Response& res) {
    if (!server_key_ok(ctx, req, res)) return;
    std::unique_ptr<animator::Session> session;
    try {
      if (req.is_multipart_form_data()) {
        if (!req.has_file("character"))
          return send_error(res, 400, "character: a file field \"character\" is required");
        const httplib::MultipartFormData file = req.get_file_value("character");
        std::optional<double> bvh_scale;
        if (req.has_file("units")) {
          try {
            bvh_scale = io::parse_bvh_import_unit(req.get_file_value("units").content, "units");
          } catch (const std::invalid_argument& e) {
            return send_error(res, 400, e.what());
          }
        }
        session = session_from_upload("character", file.filename, file.content, ctx.temp_root,
                                      ctx.uploads, bvh_scale, resource_fields(req));
      } else {
        if (req.body.size() > kMaxJsonBodyBytes)
          return send_error(res, 413, "body: larger than 1 MiB");
        const json body = json::parse(req.body, nullptr, false);
        if (body.is_discarded() || !body.is_object())
          return send_error(res, 400, "body: must be a JSON object");
        if (!body.contains("character") || !body["character"].is_string()) {
          return send_error(
              res, 400,
              "character: a bundled character name is required (see GET /api/characters)");
        }
        const std::string name = body["character"];
        if (!ctx.served_character_name.empty() && name == ctx.served_character_name) {
          session = session_from_file(ctx.served_character_path, name, ctx.uploads.limits);
        }
        bool bundled = session != nullptr;
        for (const auto& c : io::bundled_characters()) bundled = bundled || c.name == name;
        if (!bundled) {
          return send_error(res, 400,
                            "character: \"" + safe_file_name(name, "?") +
                                "\" is not a bundled character (rule: a name from GET "
                                "/api/characters; files are uploaded)");
        }
        if (!session)
          session = std::make_unique<animator::Session>(io::load_character(name).model, name);
      }
      const SessionHandle handle = ctx.registry->create(std::move(session));
      send_json(res, 201, {{"id", handle.id}, {"token", handle.token}});
    } catch (const UploadError& e) {
      send_error(res, e.status, e.what());
    }
  });
  http.Get(R"(/api/sessions/([^/]+))", [&ctx](const httplib::Request& req, httplib::Response& res) {
    const auto actor = session_of(ctx, req, res);
    if (!actor) return;
    send_json(res, 200,
              actor->call_within(ctx.call_timeout, [id = actor->id()](animator::Session& s) {
                return snapshot_json(s, id);
              }));
  });
  // the skinned mesh, once per session: it never changes, so the browser keeps it (an ETag from
  // the session and the mesh's counts; encoded only when the browser does not have it)
  http.Get(
      R"(/api/sessions/([^/]+)/mesh)", [&ctx](const httplib::Request& req, httplib::Response& res) {
        const auto actor = session_of(ctx, req, res);
        if (!actor) return;
        struct Answer {
          bool skinned = false;
          std::string etag;
          std::string bytes;  // empty when the browser's copy is current
        };
        const Answer a = actor->call_within(
            ctx.call_timeout,
            [id = actor->id(), seen = req.get_header_value("If-None-Match")](animator::Session& s) {
              Answer out;
              if (!s.skin()) return out;
              out.skinned = true;
              out.etag = "\"" + id + "-" + std::to_string(s.skin()->positions.size()) + "-" +
                         std::to_string(s.skin()->triangles.size()) + "\"";
              if (seen != out.etag) out.bytes = encode_mesh_binary(*s.skin());
              return out;
            });
        if (!a.skinned)
          return send_error(res, 404, "mesh: this session's character has no skinned mesh");
        res.set_header("ETag", a.etag);
        res.set_header("Cache-Control", "private, no-cache");
        if (a.bytes.empty()) {
          res.status = 304;
          return;
        }
        res.status = 200;
        res.set_content(a.bytes, "application/octet-stream");
      });
  // the measured markers of the trial the clip was fitted to (docs/protocol.md, "Markers"): they
  // change only with the clip, so the revision is the ETag; encoded outside the session's actor
  // (they are immutable and shared)
  http.Get(R"(/api/sessions/([^/]+)/markers)", [&ctx](const httplib::Request& req,
                                                      httplib::Response& res) {
    const auto actor = session_of(ctx, req, res);
    if (!actor) return;
    const std::shared_ptr<const animator::ClipMarkers> markers = actor->call_within(
        ctx.call_timeout, [](animator::Session& s) { return s.document().markers; });
    if (!markers) {
      return send_error(res, 404, "markers: this session's clip was not fitted to a marker trial");
    }
    const std::string etag = "\"" + std::to_string(markers->revision) + "\"";
    res.set_header("ETag", etag);
    res.set_header("Cache-Control", "private, no-cache");
    if (req.get_header_value("If-None-Match") == etag) {
      res.status = 304;
      return;
    }
    json body = animator::clip_markers_to_json(actor->model(), *markers);
    body["revision"] = markers->revision;
    send_json(res, 200, body);
  });
  http.Post(
      R"(/api/sessions/([^/]+)/clip)", [&ctx](const httplib::Request& req, httplib::Response& res) {
        const auto actor = session_of(ctx, req, res);
        if (!actor) return;
        if (!has_clip_file(req, res)) return;
        try {
          const httplib::MultipartFormData file = req.get_file_value("clip");
          const bool retarget = req.get_param_value("retarget") == "1";
          std::vector<animator::MappingEntry> mapping;
          if (req.has_file("mapping")) mapping = mapping_field(req.get_file_value("mapping"));
          ClipUpload upload =
              clip_from_upload("clip", file.filename, file.content, actor->model(), ctx.temp_root,
                               ctx.uploads, retarget, mapping, resource_fields(req));
          json answer{{"frames", upload.clip.size()}, {"frame_time", upload.clip.frame_time}};
          if (upload.markers) answer["markers"] = upload.markers->set.size();
          auto shared = std::make_shared<ClipUpload>(std::move(upload));
          actor->call_within(
              ctx.call_timeout,
              [shared](animator::Session& s) {
                s.set_clip(std::move(shared->clip), "import clip", std::move(shared->markers));
              },
              /*edit=*/true);
          send_json(res, 200, answer);
        } catch (const UploadError& e) {
          if (e.code.empty()) return send_error(res, e.status, e.what());
          send_json(res, e.status, {{"error", e.what()}, {"code", e.code}});
        }
      });
  // the correspondence retargeting would guess for a clip file, for the page's mapping editor;
  // the session is not changed
  http.Post(R"(/api/sessions/([^/]+)/clip/correspondence)",
            [&ctx](const httplib::Request& req, httplib::Response& res) {
              const auto actor = session_of(ctx, req, res);
              if (!actor) return;
              if (!has_clip_file(req, res)) return;
              try {
                const httplib::MultipartFormData file = req.get_file_value("clip");
                send_json(res, 200,
                          clip_correspondence("clip", file.filename, file.content, actor->model(),
                                              ctx.temp_root, ctx.uploads, resource_fields(req)));
              } catch (const UploadError& e) {
                send_error(res, e.status, e.what());
              }
            });
  http.Get(R"(/api/sessions/([^/]+)/export)", [&ctx](const httplib::Request& req,
                                                     httplib::Response& res) {
    const auto actor = session_of(ctx, req, res);
    if (!actor) return;
    const std::string format = req.get_param_value("format");
    if (format != "bvh" && format != "gltf" && format != "glb") {
      return send_error(res, 400, "format: must be bvh, gltf or glb");
    }
    std::optional<int> first, last;
    io::BvhExportOptions bvh;
    try {
      first = int_param(req, "first", res, 0, kMaxFrameParam);
      last = int_param(req, "last", res, 0, kMaxFrameParam);
      bvh = bvh_params(req, format, res);
    } catch (const std::invalid_argument&) {
      return;
    }
    struct Animation {
      core::Clip clip;
      std::string name;
      const core::SkinnedMesh* skin;
      std::shared_ptr<const io::BvhLayout> bvh_source;
    };
    // only the frames asked for are sampled; the whole animation is refused when it is longer
    // than the clip budget (a session restored from a file made under other limits)
    const Animation a = actor->call_within(ctx.call_timeout, [first, last](animator::Session& s) {
      const std::int64_t end = s.animation_frames() - 1;
      return Animation{s.animation_clip(first.value_or(0), last.value_or(end)), s.character(),
                       s.skin(), s.bvh_source()};
    });
    const std::string file_name = safe_file_name(a.name, "animation") + "." + format;
    try {
      if (format == "bvh") {
        bvh.layout = a.bvh_source.get();
        set_uncompressed(res, io::write_bvh(actor->model(), a.clip, bvh),
                         "text/plain; charset=utf-8");
      } else {
        // without a skinned mesh, the character's shapes make the mesh every viewer draws
        const io::GltfExportOptions gltf{.name = a.name,
                                         .shape_mesh = a.skin == nullptr || a.skin->empty()};
        if (format == "gltf") {
          res.set_content(io::write_gltf(actor->model(), &a.clip, a.skin, gltf), "model/gltf+json");
        } else {
          const std::vector<std::uint8_t> glb =
              io::write_glb(actor->model(), &a.clip, a.skin, gltf);
          res.set_content(std::string(glb.begin(), glb.end()), "model/gltf-binary");
        }
      }
    } catch (const std::invalid_argument& e) {
      return send_error(res, 422, std::string("export: ") + e.what());
    }
    res.set_header("Content-Disposition", "attachment; filename=\"" + file_name + "\"");
  });
  http.Get(R"(/api/sessions/([^/]+)/thumbnail\.png)",
           [&ctx](const httplib::Request& req, httplib::Response& res) {
             const auto actor = session_of(ctx, req, res);
             if (!actor) return;
             std::optional<int> frame, size;
             try {
               frame = int_param(req, "frame", res, 0, kMaxFrameParam);
               size = int_param(req, "size", res, 16, 1024);
             } catch (const std::invalid_argument&) {
               return;
             }
             struct Pose {
               Eigen::VectorXd q;
               const core::SkinnedMesh* skin;
               std::int64_t frames;
             };
             // one frame, sampled from the clip, layers and keys directly
             const Pose pose = actor->call_within(ctx.call_timeout, [frame](animator::Session& s) {
               if (!frame) return Pose{s.q(), s.skin(), 0};
               const std::int64_t frames = s.animation_frames();
               if (*frame >= frames) return Pose{Eigen::VectorXd(), s.skin(), frames};
               Pose p{Eigen::VectorXd(), s.skin(), frames};
               s.animation_frame(*frame, p.q);
               return p;
             });
             if (pose.q.size() == 0) {
               return send_error(res, 400,
                                 "frame: must be below the animation's " +
                                     std::to_string(pose.frames) + " frames");
             }
#if PINDRAG_HAVE_THUMBNAIL
             static ThumbnailCache cache;
             ThumbnailOptions options;
             options.size = size.value_or(128);
             options.cache = &cache;
             try {
               const std::vector<std::uint8_t> png =
                   render_thumbnail(actor->model(), pose.q, options, pose.skin);
               res.set_header("Cache-Control", "no-cache");
               res.set_content(std::string(png.begin(), png.end()), "image/png");
             } catch (const std::invalid_argument& e) {
               send_error(res, 400, std::string("thumbnail: ") + e.what());
             } catch (const std::runtime_error& e) {
               send_error(res, 503, std::string("thumbnail: ") + e.what());
             }
#else
             send_error(res, 501, "thumbnail: this build has no thumbnail renderer");
#endif
           });
}

}  // namespace

void register_routes(httplib::Server& http, const RouteContext& context) {
  const RouteContext& ctx = context;
  // the largest file plus its multipart framing; each file type's own cap is checked after
  http.set_payload_max_length(ctx.uploads.caps.largest() + (std::size_t{1} << 16));
  http.set_keep_alive_timeout(1);  // shutdown waits for idle keep-alive connections
  http.set_pre_routing_handler([&ctx](const httplib::Request& req, httplib::Response& res) {
    if (!ctx.policy->host_allowed(req.get_header_value("Host"), ctx.policy->http_port())) {
      send_error(
          res, 403,
          "Host: not a name of this server (rule: 127.0.0.1, localhost or [::1] with the port)");
      return httplib::Server::HandlerResponse::Handled;
    }
    if (is_state_changing(req.method)) {
      if (req.has_header("Origin")) {
        if (!ctx.policy->origin_allowed(req.get_header_value("Origin"))) {
          send_error(
              res, 403,
              "Origin: not this server's page (rule: exactly " + ctx.policy->page_origin() + ")");
          return httplib::Server::HandlerResponse::Handled;
        }
      } else if (req.path == "/api/sessions" && !is_loopback_address(req.remote_addr)) {
        send_error(res, 403, "Origin: required for creating a session from another machine");
        return httplib::Server::HandlerResponse::Handled;
      }
    }
    return httplib::Server::HandlerResponse::Unhandled;
  });
  http.set_error_handler([&ctx](const httplib::Request&, httplib::Response& res) {
    if (!res.body.empty()) return;
    const std::string too_large = "body: larger than the largest upload cap, " +
                                  byte_text(ctx.uploads.caps.largest()) +
                                  " (set by pindrag serve --max-upload-<type>)";
    const std::string what = res.status == 413   ? too_large
                             : res.status == 404 ? "path: no such route"
                             : res.status == 405 ? "method: not allowed on this route"
                                                 : "request: refused";
    send_error(res, res.status, what);
  });
  http.set_exception_handler(
      [](const httplib::Request&, httplib::Response& res, std::exception_ptr error) {
        std::string what = "internal error";
        try {
          if (error) std::rethrow_exception(error);
        } catch (const ActorBusy& e) {
          res.set_header("Retry-After", kRetryAfterSeconds);
          return send_error(res, 503, e.what());
        } catch (const SessionsBusy& e) {
          res.set_header("Retry-After", kRetryAfterSeconds);
          return send_error(res, 503, e.what());
        } catch (const animator::SessionWriteError& e) {
          // the server could not save: its fault, not the request's
          return send_error(res, e.out_of_space() ? 507 : 503, e.what());
        } catch (const std::system_error& e) {
          const int err = e.code().value();
          if (err == ENOSPC || err == EDQUOT || err == EFBIG) {
            return send_error(res, 507, std::string("storage: ") + e.code().message());
          }
          what = e.what();
        } catch (const animator::BudgetError& e) {
          return send_error(res, 422, e.what());  // over a limit: names it and its setting
        } catch (const animator::SessionError& e) {
          return send_error(res, 400, e.what());
        } catch (const std::exception& e) {
          what = e.what();
        } catch (...) {
        }
        send_error(res, 500, what);
      });
  register_api(http, ctx);
  register_session_list(http, ctx);
  register_static(http, ctx);
}

}  // namespace server
