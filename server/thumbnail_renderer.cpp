#include "server/thumbnail_renderer.hpp"

#define GL_GLEXT_PROTOTYPES 1
#include <GL/gl.h>
#include <GL/glext.h>
#include <GL/osmesa.h>

#include <algorithm>
#include <cstddef>
#include <cstdio>
#include <mutex>
#include <set>
#include <stdexcept>
#include <string>
#include <utility>

#include "server/thumbnail.hpp"

namespace server {

namespace {

constexpr int kWantedSamples = 4;

// the figure: world-space lighting (key, fill, sky/ground ambient, a faint rim), output in sRGB
constexpr const char* kFigureVertexShader = R"(#version 330 core
layout(location = 0) in vec3 a_position;
layout(location = 1) in vec3 a_normal;
layout(location = 2) in vec3 a_colour;
uniform mat4 u_view_projection;
out vec3 v_position;
out vec3 v_normal;
out vec3 v_colour;
void main() {
  v_position = a_position;
  v_normal = a_normal;
  v_colour = a_colour;
  gl_Position = u_view_projection * vec4(a_position, 1.0);
}
)";
constexpr const char* kFigureFragmentShader = R"(#version 330 core
in vec3 v_position;
in vec3 v_normal;
in vec3 v_colour;
uniform vec3 u_eye;
out vec4 o_colour;
const vec3 kKey = normalize(vec3(-0.35, 0.85, 0.55));
const vec3 kFill = normalize(vec3(0.8, 0.2, 0.3));
const vec3 kSky = vec3(0.55, 0.6, 0.7);
const vec3 kGround = vec3(0.25, 0.22, 0.2);
void main() {
  vec3 n = normalize(v_normal);
  vec3 view = normalize(u_eye - v_position);
  // two-sided: the inside of an open surface is lit like its outside
  if (dot(n, view) < 0.0) n = -n;
  float key = max(dot(n, kKey), 0.0);
  float fill = max(dot(n, kFill), 0.0);
  vec3 ambient = mix(kGround, kSky, 0.5 + 0.5 * n.y);
  vec3 half_vector = normalize(kKey + view);
  float specular = key > 0.0 ? 0.18 * pow(max(dot(n, half_vector), 0.0), 40.0) : 0.0;
  float rim = 0.12 * pow(1.0 - max(dot(n, view), 0.0), 3.0);
  vec3 linear = v_colour * (0.85 * key + 0.25 * fill + 0.55 * ambient) + vec3(specular + rim);
  o_colour = vec4(pow(clamp(linear, 0.0, 1.0), vec3(1.0 / 2.2)), 1.0);
}
)";

// the ground: a soft shadow disc and a grid fading out with the distance from the figure, mixed
// into the background (all in sRGB); fragments with neither are discarded, leaving the clear colour
constexpr const char* kGroundVertexShader = R"(#version 330 core
layout(location = 0) in vec2 a_corner;
uniform mat4 u_view_projection;
uniform float u_ground_y;
uniform float u_half_side;
out vec2 v_xz;
void main() {
  v_xz = a_corner * u_half_side;
  gl_Position = u_view_projection * vec4(v_xz.x, u_ground_y, v_xz.y, 1.0);
}
)";
constexpr const char* kGroundFragmentShader = R"(#version 330 core
in vec2 v_xz;
uniform vec3 u_background;
uniform float u_fade_radius;
uniform float u_shadow_radius;
uniform float u_grid_step;
uniform int u_draw_grid;
out vec4 o_colour;
void main() {
  float r = length(v_xz);
  float shadow = 0.28 * exp(-3.0 * (r * r) / (u_shadow_radius * u_shadow_radius));
  float grid = 0.0;
  if (u_draw_grid != 0) {
    vec2 cell = v_xz / u_grid_step;
    vec2 width = fwidth(cell);
    vec2 distance_to_line = abs(fract(cell - 0.5) - 0.5) / max(width, vec2(1e-6));
    float line = 1.0 - min(min(distance_to_line.x, distance_to_line.y), 1.0);
    // lines thinner than a pixel apart would alias: fade them out
    float resolvable = 1.0 - smoothstep(0.25, 0.5, max(width.x, width.y));
    float fade = 1.0 - smoothstep(0.3 * u_fade_radius, u_fade_radius, r);
    grid = 0.3 * line * fade * resolvable;
  }
  if (shadow < 0.002 && grid < 0.002) discard;
  vec3 colour = mix(u_background, vec3(0.45, 0.47, 0.52), grid) * (1.0 - shadow);
  o_colour = vec4(colour, 1.0);
}
)";

std::string gl_string(GLenum name) {
  const auto* s = reinterpret_cast<const char*>(glGetString(name));
  return s ? s : "";
}

void check_gl(const char* step) {
  const GLenum error = glGetError();
  if (error != GL_NO_ERROR) {
    char code[16];
    std::snprintf(code, sizeof code, "0x%04X", error);
    throw std::runtime_error(std::string("thumbnail: GL error ") + code + " during " + step);
  }
}

enum class GlKind { kShader, kProgram, kBuffer, kVertexArray, kFramebuffer, kRenderbuffer };

// The process-wide renderer. Every member is guarded by `mutex`.
class Renderer {
 public:
  std::mutex mutex;

  std::vector<std::uint8_t> draw(const ThumbnailScene& scene);
  ThumbnailRendererStats stats();
  void release();

 private:
  // makes the context current on this thread for its lifetime
  class Current {
   public:
    explicit Current(Renderer& r) {
      if (!OSMesaMakeCurrent(r.context_, r.default_pixels_.data(), GL_UNSIGNED_BYTE, kDefaultSide,
                             kDefaultSide))
        throw std::runtime_error("thumbnail: OSMesaMakeCurrent failed");
    }
    ~Current() { OSMesaMakeCurrent(nullptr, nullptr, 0, 0, 0); }
    Current(const Current&) = delete;
    Current& operator=(const Current&) = delete;
  };

  void create_context();
  void create_objects();
  void ensure_framebuffers(int size);
  void delete_framebuffers();
  GLuint compile_program(const char* vertex, const char* fragment, const char* what);
  GLuint track(GlKind kind, GLuint name);
  int alive_objects() const;

  // the default framebuffer is never drawn to: renders go to the framebuffer objects below
  static constexpr int kDefaultSide = 16;
  std::vector<std::uint8_t> default_pixels_ =
      std::vector<std::uint8_t>(std::size_t{kDefaultSide} * kDefaultSide * 4);
  OSMesaContext context_ = nullptr;
  std::set<std::pair<GlKind, GLuint>> created_;  // every name created, for the leak check
  std::uint64_t renders_ = 0;
  int samples_ = 0;
  std::string version_, renderer_;

  GLuint figure_program_ = 0, ground_program_ = 0;
  GLint figure_view_projection_ = -1, figure_eye_ = -1;
  GLint ground_view_projection_ = -1, ground_y_ = -1, ground_half_side_ = -1,
        ground_background_ = -1, ground_fade_ = -1, ground_shadow_ = -1, ground_step_ = -1,
        ground_draw_grid_ = -1;
  GLuint figure_vao_ = 0, figure_vertices_ = 0, figure_indices_ = 0;
  GLuint ground_vao_ = 0, ground_vertices_ = 0;
  // sized framebuffers: multisampled colour + depth, and the single-sample resolve target
  int framebuffer_size_ = 0;
  GLuint msaa_fbo_ = 0, msaa_colour_ = 0, msaa_depth_ = 0, resolve_fbo_ = 0, resolve_colour_ = 0;
};

GLuint Renderer::track(GlKind kind, GLuint name) {
  created_.insert({kind, name});
  return name;
}

int Renderer::alive_objects() const {
  int alive = 0;
  for (const auto& [kind, name] : created_) {
    GLboolean is = GL_FALSE;
    switch (kind) {
      case GlKind::kShader:
        is = glIsShader(name);
        break;
      case GlKind::kProgram:
        is = glIsProgram(name);
        break;
      case GlKind::kBuffer:
        is = glIsBuffer(name);
        break;
      case GlKind::kVertexArray:
        is = glIsVertexArray(name);
        break;
      case GlKind::kFramebuffer:
        is = glIsFramebuffer(name);
        break;
      case GlKind::kRenderbuffer:
        is = glIsRenderbuffer(name);
        break;
    }
    alive += is == GL_TRUE;
  }
  return alive;
}

void Renderer::create_context() {
  const int attributes[] = {OSMESA_FORMAT,
                            OSMESA_RGBA,
                            OSMESA_DEPTH_BITS,
                            24,
                            OSMESA_PROFILE,
                            OSMESA_CORE_PROFILE,
                            OSMESA_CONTEXT_MAJOR_VERSION,
                            3,
                            OSMESA_CONTEXT_MINOR_VERSION,
                            3,
                            0};
  context_ = OSMesaCreateContextAttribs(attributes, nullptr);
  if (!context_)
    throw std::runtime_error("thumbnail: OSMesa cannot create a GL 3.3 core profile context");
  try {
    Current current(*this);
    version_ = gl_string(GL_VERSION);
    renderer_ = gl_string(GL_RENDERER);
    if (version_.empty())
      throw std::runtime_error("thumbnail: glGetString(GL_VERSION) is empty (is libGL linked?)");
    GLint max_samples = 0;
    glGetIntegerv(GL_MAX_SAMPLES, &max_samples);
    samples_ = std::min(kWantedSamples, std::max(max_samples, 0));
    create_objects();
  } catch (...) {
    release();
    throw;
  }
}

GLuint Renderer::compile_program(const char* vertex, const char* fragment, const char* what) {
  auto compile = [&](GLenum type, const char* source) {
    const GLuint shader = track(GlKind::kShader, glCreateShader(type));
    glShaderSource(shader, 1, &source, nullptr);
    glCompileShader(shader);
    GLint ok = GL_FALSE;
    glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
    if (!ok) {
      char log[1024] = {};
      glGetShaderInfoLog(shader, sizeof log, nullptr, log);
      glDeleteShader(shader);
      throw std::runtime_error(std::string("thumbnail: the ") + what +
                               " shader does not compile: " + log);
    }
    return shader;
  };
  const GLuint vs = compile(GL_VERTEX_SHADER, vertex);
  GLuint fs = 0;
  try {
    fs = compile(GL_FRAGMENT_SHADER, fragment);
  } catch (...) {
    glDeleteShader(vs);
    throw;
  }
  const GLuint program = track(GlKind::kProgram, glCreateProgram());
  glAttachShader(program, vs);
  glAttachShader(program, fs);
  glLinkProgram(program);
  // the program keeps what it needs: the shaders go now
  glDetachShader(program, vs);
  glDetachShader(program, fs);
  glDeleteShader(vs);
  glDeleteShader(fs);
  GLint ok = GL_FALSE;
  glGetProgramiv(program, GL_LINK_STATUS, &ok);
  if (!ok) {
    char log[1024] = {};
    glGetProgramInfoLog(program, sizeof log, nullptr, log);
    glDeleteProgram(program);
    throw std::runtime_error(std::string("thumbnail: the ") + what +
                             " program does not link: " + log);
  }
  return program;
}

void Renderer::create_objects() {
  figure_program_ = compile_program(kFigureVertexShader, kFigureFragmentShader, "figure");
  figure_view_projection_ = glGetUniformLocation(figure_program_, "u_view_projection");
  figure_eye_ = glGetUniformLocation(figure_program_, "u_eye");
  ground_program_ = compile_program(kGroundVertexShader, kGroundFragmentShader, "ground");
  ground_view_projection_ = glGetUniformLocation(ground_program_, "u_view_projection");
  ground_y_ = glGetUniformLocation(ground_program_, "u_ground_y");
  ground_half_side_ = glGetUniformLocation(ground_program_, "u_half_side");
  ground_background_ = glGetUniformLocation(ground_program_, "u_background");
  ground_fade_ = glGetUniformLocation(ground_program_, "u_fade_radius");
  ground_shadow_ = glGetUniformLocation(ground_program_, "u_shadow_radius");
  ground_step_ = glGetUniformLocation(ground_program_, "u_grid_step");
  ground_draw_grid_ = glGetUniformLocation(ground_program_, "u_draw_grid");

  // figure: interleaved position, normal, colour; contents uploaded per render
  GLuint names[2];
  glGenVertexArrays(1, &figure_vao_);
  track(GlKind::kVertexArray, figure_vao_);
  glGenBuffers(2, names);
  figure_vertices_ = track(GlKind::kBuffer, names[0]);
  figure_indices_ = track(GlKind::kBuffer, names[1]);
  glBindVertexArray(figure_vao_);
  glBindBuffer(GL_ARRAY_BUFFER, figure_vertices_);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, figure_indices_);
  const GLsizei stride = io::TriangleMesh::kFloatsPerVertex * sizeof(float);
  for (GLuint attribute = 0; attribute < 3; ++attribute) {
    glEnableVertexAttribArray(attribute);
    glVertexAttribPointer(
        attribute, 3, GL_FLOAT, GL_FALSE, stride,
        reinterpret_cast<const void*>(std::size_t{attribute} * 3 * sizeof(float)));
  }

  // ground: a unit square scaled in the shader, drawn as a strip
  const float corners[] = {-1, -1, 1, -1, -1, 1, 1, 1};
  glGenVertexArrays(1, &ground_vao_);
  track(GlKind::kVertexArray, ground_vao_);
  glGenBuffers(1, &ground_vertices_);
  track(GlKind::kBuffer, ground_vertices_);
  glBindVertexArray(ground_vao_);
  glBindBuffer(GL_ARRAY_BUFFER, ground_vertices_);
  glBufferData(GL_ARRAY_BUFFER, sizeof corners, corners, GL_STATIC_DRAW);
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 2, GL_FLOAT, GL_FALSE, 2 * sizeof(float), nullptr);
  glBindVertexArray(0);
  check_gl("setup");
}

void Renderer::delete_framebuffers() {
  if (framebuffer_size_ == 0) return;
  const GLuint fbos[] = {msaa_fbo_, resolve_fbo_};
  const GLuint rbos[] = {msaa_colour_, msaa_depth_, resolve_colour_};
  glDeleteFramebuffers(2, fbos);
  glDeleteRenderbuffers(3, rbos);
  msaa_fbo_ = msaa_colour_ = msaa_depth_ = resolve_fbo_ = resolve_colour_ = 0;
  framebuffer_size_ = 0;
}

void Renderer::ensure_framebuffers(int size) {
  if (framebuffer_size_ == size) return;
  // replaced, not added to: the previous size's objects go first
  delete_framebuffers();
  GLuint fbos[2], rbos[3];
  glGenFramebuffers(2, fbos);
  glGenRenderbuffers(3, rbos);
  msaa_fbo_ = track(GlKind::kFramebuffer, fbos[0]);
  resolve_fbo_ = track(GlKind::kFramebuffer, fbos[1]);
  msaa_colour_ = track(GlKind::kRenderbuffer, rbos[0]);
  msaa_depth_ = track(GlKind::kRenderbuffer, rbos[1]);
  resolve_colour_ = track(GlKind::kRenderbuffer, rbos[2]);
  framebuffer_size_ = size;

  glBindRenderbuffer(GL_RENDERBUFFER, msaa_colour_);
  glRenderbufferStorageMultisample(GL_RENDERBUFFER, samples_, GL_RGBA8, size, size);
  glBindRenderbuffer(GL_RENDERBUFFER, msaa_depth_);
  glRenderbufferStorageMultisample(GL_RENDERBUFFER, samples_, GL_DEPTH_COMPONENT24, size, size);
  glBindRenderbuffer(GL_RENDERBUFFER, resolve_colour_);
  glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, size, size);
  glBindRenderbuffer(GL_RENDERBUFFER, 0);

  glBindFramebuffer(GL_FRAMEBUFFER, msaa_fbo_);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, msaa_colour_);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, msaa_depth_);
  const GLenum msaa_status = glCheckFramebufferStatus(GL_FRAMEBUFFER);
  glBindFramebuffer(GL_FRAMEBUFFER, resolve_fbo_);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, resolve_colour_);
  const GLenum resolve_status = glCheckFramebufferStatus(GL_FRAMEBUFFER);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  if (msaa_status != GL_FRAMEBUFFER_COMPLETE || resolve_status != GL_FRAMEBUFFER_COMPLETE) {
    delete_framebuffers();
    throw std::runtime_error("thumbnail: framebuffer of " + std::to_string(size) +
                             " px is incomplete");
  }
  check_gl("framebuffer setup");
}

std::vector<std::uint8_t> Renderer::draw(const ThumbnailScene& scene) {
  if (!context_) create_context();
  Current current(*this);
  ensure_framebuffers(scene.size);
  const int size = scene.size;

  glBindFramebuffer(GL_FRAMEBUFFER, msaa_fbo_);
  glViewport(0, 0, size, size);
  glClearColor(scene.background[0], scene.background[1], scene.background[2], 1.0f);
  glClearDepth(1.0);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glDisable(GL_CULL_FACE);

  if (scene.draw_shadow) {
    glUseProgram(ground_program_);
    glUniformMatrix4fv(ground_view_projection_, 1, GL_FALSE, scene.view_projection.data());
    glUniform1f(ground_y_, scene.ground_y);
    glUniform1f(ground_half_side_, scene.fade_radius);
    glUniform3f(ground_background_, scene.background[0], scene.background[1], scene.background[2]);
    glUniform1f(ground_fade_, scene.fade_radius);
    glUniform1f(ground_shadow_, scene.shadow_radius);
    glUniform1f(ground_step_, scene.grid_step);
    glUniform1i(ground_draw_grid_, scene.draw_grid ? 1 : 0);
    glBindVertexArray(ground_vao_);
    glDrawArrays(GL_TRIANGLE_STRIP, 0, 4);
  }

  if (!scene.figure.indices.empty()) {
    glUseProgram(figure_program_);
    glUniformMatrix4fv(figure_view_projection_, 1, GL_FALSE, scene.view_projection.data());
    glUniform3fv(figure_eye_, 1, scene.eye_F.data());
    glBindVertexArray(figure_vao_);
    // new storage for the same buffer names each render (the element buffer is the VAO's; the
    // array buffer binding is not part of it)
    glBindBuffer(GL_ARRAY_BUFFER, figure_vertices_);
    glBufferData(GL_ARRAY_BUFFER, scene.figure.vertices.size() * sizeof(float),
                 scene.figure.vertices.data(), GL_STREAM_DRAW);
    glBufferData(GL_ELEMENT_ARRAY_BUFFER, scene.figure.indices.size() * sizeof(std::uint32_t),
                 scene.figure.indices.data(), GL_STREAM_DRAW);
    glDrawElements(GL_TRIANGLES, static_cast<GLsizei>(scene.figure.indices.size()), GL_UNSIGNED_INT,
                   nullptr);
  }
  glBindVertexArray(0);
  glUseProgram(0);

  // resolve the samples, then read back (GL rows run bottom to top)
  glBindFramebuffer(GL_READ_FRAMEBUFFER, msaa_fbo_);
  glBindFramebuffer(GL_DRAW_FRAMEBUFFER, resolve_fbo_);
  glBlitFramebuffer(0, 0, size, size, 0, 0, size, size, GL_COLOR_BUFFER_BIT, GL_NEAREST);
  glBindFramebuffer(GL_READ_FRAMEBUFFER, resolve_fbo_);
  std::vector<std::uint8_t> rgba(std::size_t{4} * size * size);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(0, 0, size, size, GL_RGBA, GL_UNSIGNED_BYTE, rgba.data());
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  // drop the mesh storage: a big skin should not stay allocated between renders
  glBindVertexArray(figure_vao_);
  glBindBuffer(GL_ARRAY_BUFFER, figure_vertices_);
  glBufferData(GL_ARRAY_BUFFER, 0, nullptr, GL_STREAM_DRAW);
  glBufferData(GL_ELEMENT_ARRAY_BUFFER, 0, nullptr, GL_STREAM_DRAW);
  glBindBuffer(GL_ARRAY_BUFFER, 0);
  glBindVertexArray(0);
  check_gl("render");
  ++renders_;
  return rgba;
}

ThumbnailRendererStats Renderer::stats() {
  ThumbnailRendererStats s;
  if (!context_) return s;
  Current current(*this);
  s.context_alive = true;
  s.gl_objects = alive_objects();
  s.renders = renders_;
  s.samples = samples_;
  s.gl_version = version_;
  s.gl_renderer = renderer_;
  return s;
}

void Renderer::release() {
  if (!context_) return;
  {
    Current current(*this);
    delete_framebuffers();
    const GLuint vaos[] = {figure_vao_, ground_vao_};
    const GLuint buffers[] = {figure_vertices_, figure_indices_, ground_vertices_};
    glDeleteVertexArrays(2, vaos);
    glDeleteBuffers(3, buffers);
    glDeleteProgram(figure_program_);
    glDeleteProgram(ground_program_);
    glFinish();
  }
  OSMesaDestroyContext(context_);
  context_ = nullptr;
  created_.clear();
  renders_ = 0;
  samples_ = 0;
  figure_program_ = ground_program_ = 0;
  figure_vao_ = figure_vertices_ = figure_indices_ = ground_vao_ = ground_vertices_ = 0;
}

// never destroyed: Mesa's own exit handlers may run before static destructors would
Renderer& renderer() {
  static Renderer* const instance = new Renderer;
  return *instance;
}

}  // namespace

std::vector<std::uint8_t> draw_thumbnail_scene(const ThumbnailScene& scene) {
  std::vector<std::uint8_t> rgba;
  {
    Renderer& r = renderer();
    std::lock_guard lock(r.mutex);
    rgba = r.draw(scene);
  }
  // RGBA bottom-up → RGB top-down, outside the lock
  const std::size_t size = static_cast<std::size_t>(scene.size);
  std::vector<std::uint8_t> rgb(size * size * 3);
  for (std::size_t row = 0; row < size; ++row) {
    const std::uint8_t* src = rgba.data() + (size - 1 - row) * size * 4;
    std::uint8_t* dst = rgb.data() + row * size * 3;
    for (std::size_t x = 0; x < size; ++x) {
      dst[3 * x] = src[4 * x];
      dst[3 * x + 1] = src[4 * x + 1];
      dst[3 * x + 2] = src[4 * x + 2];
    }
  }
  return rgb;
}

ThumbnailRendererStats thumbnail_renderer_stats() {
  Renderer& r = renderer();
  std::lock_guard lock(r.mutex);
  return r.stats();
}

void release_thumbnail_renderer() {
  Renderer& r = renderer();
  std::lock_guard lock(r.mutex);
  r.release();
}

}  // namespace server

#undef GL_GLEXT_PROTOTYPES  // a batch build compiles the next file in this unit
