// Tests for server/thumbnail.hpp: the PNG decodes (libpng) to the requested size; the figure is
// drawn, framed (centred, ~80 % of the height) and tinted by side; poses, skins and options change
// the image; bad input names its field; the cache hits and evicts; many threads render at once
// with the same results as one; renders leave no GL objects behind.
#include "server/thumbnail.hpp"

#include <gtest/gtest.h>
#include <png.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <set>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "core/configuration.hpp"
#include "core/human_figure.hpp"
#include "io/assimp_import.hpp"
#include "tests/fixtures/fixtures.hpp"

// Under LeakSanitizer: tests/server/lsan_mesa.supp, which names Mesa's library only.
#ifdef PINDRAG_LSAN_SUPPRESSIONS
extern "C" const char* __lsan_default_options() {
  return "suppressions=" PINDRAG_LSAN_SUPPRESSIONS;
}
#endif

namespace {

using Bytes = std::vector<std::uint8_t>;

struct Image {
  int width = 0, height = 0;
  std::vector<std::uint8_t> rgb;
  const std::uint8_t* at(int x, int y) const {
    return rgb.data() + (static_cast<std::size_t>(y) * width + x) * 3;
  }
};

// decoded by libpng, independently of the encoder's code path
Image decode(const Bytes& png) {
  png_image image{};
  image.version = PNG_IMAGE_VERSION;
  if (!png_image_begin_read_from_memory(&image, png.data(), png.size()))
    throw std::runtime_error(std::string("libpng cannot read the PNG: ") + image.message);
  image.format = PNG_FORMAT_RGB;
  Image out;
  out.width = static_cast<int>(image.width);
  out.height = static_cast<int>(image.height);
  out.rgb.resize(PNG_IMAGE_SIZE(image));
  if (!png_image_finish_read(&image, nullptr, out.rgb.data(), 0, nullptr))
    throw std::runtime_error(std::string("libpng cannot decode the PNG: ") + image.message);
  return out;
}

// the images are written to $PINDRAG_THUMBNAIL_OUT when it is set, for looking at them
void keep(const Bytes& png, const std::string& name) {
  const char* dir = std::getenv("PINDRAG_THUMBNAIL_OUT");
  if (dir == nullptr) return;
  std::filesystem::create_directories(dir);
  std::ofstream(std::string(dir) + "/" + name + ".png", std::ios::binary)
      .write(reinterpret_cast<const char*>(png.data()), static_cast<std::streamsize>(png.size()));
}

bool is_background(const Image& im, int x, int y, const std::array<std::uint8_t, 3>& bg) {
  const std::uint8_t* p = im.at(x, y);
  return p[0] == bg[0] && p[1] == bg[1] && p[2] == bg[2];
}

struct Box {
  int x0 = std::numeric_limits<int>::max(), y0 = std::numeric_limits<int>::max(), x1 = -1, y1 = -1;
  int pixels = 0;
  bool empty() const { return x1 < 0; }
};
// bounding box of the pixels that differ from the background
Box figure_box(const Image& im, const std::array<std::uint8_t, 3>& bg) {
  Box b;
  for (int y = 0; y < im.height; ++y)
    for (int x = 0; x < im.width; ++x) {
      if (is_background(im, x, y, bg)) continue;
      b.x0 = std::min(b.x0, x);
      b.y0 = std::min(b.y0, y);
      b.x1 = std::max(b.x1, x);
      b.y1 = std::max(b.y1, y);
      ++b.pixels;
    }
  return b;
}

int differing_pixels(const Image& a, const Image& b) {
  int n = 0;
  for (std::size_t i = 0; i + 2 < a.rgb.size(); i += 3)
    n += a.rgb[i] != b.rgb[i] || a.rgb[i + 1] != b.rgb[i + 1] || a.rgb[i + 2] != b.rgb[i + 2];
  return n;
}

server::ThumbnailOptions plain(int size) {
  server::ThumbnailOptions o;
  o.size = size;
  o.ground = server::ThumbnailGround::kNone;
  return o;
}

// a pose that differs clearly from the neutral one: the left arm raised sideways
Eigen::VectorXd arm_raised(const core::Model& m) {
  Eigen::VectorXd q = core::neutral_configuration(m);
  const int shoulder = m.joint_index("l_shoulder");
  EXPECT_GT(shoulder, 0);
  if (shoulder > 0)
    core::set_quaternion_at(q, m.idx_q[shoulder],
                            core::Quaternion(Eigen::AngleAxisd(1.4, core::Vector3::UnitZ())));
  return q;
}

TEST(Thumbnail, PngDecodesToTheRequestedSize) {
  const auto& m = *fixtures::human48();
  for (int size : {server::kThumbnailMinSize, 64, 200, 256}) {
    server::ThumbnailOptions o;
    o.size = size;
    const Bytes png = server::render_thumbnail(m, core::neutral_configuration(m), o);
    keep(png, "human48_default_" + std::to_string(size));
    ASSERT_GT(png.size(), 8u);
    EXPECT_EQ(png[1], 'P');
    const Image im = decode(png);
    EXPECT_EQ(im.width, size);
    EXPECT_EQ(im.height, size);
  }
}

TEST(Thumbnail, FigureIsCentredAndFillsAboutEightyPercentOfTheHeight) {
  const auto& m = *fixtures::human48();
  const auto o = plain(256);
  const Bytes png = server::render_thumbnail(m, core::neutral_configuration(m), o);
  keep(png, "human48_plain");
  const Image im = decode(png);
  const Box b = figure_box(im, o.background);
  ASSERT_FALSE(b.empty()) << "blank image";
  const double height = (b.y1 - b.y0 + 1) / 256.0, width = (b.x1 - b.x0 + 1) / 256.0;
  // the bounds' box fills 80 %; the rounded shapes inside it a little less
  EXPECT_GT(height, 0.70);
  EXPECT_LE(height, 0.81);
  EXPECT_LE(width, 0.90);
  const double cx = 0.5 * (b.x0 + b.x1 + 1) / 256.0, cy = 0.5 * (b.y0 + b.y1 + 1) / 256.0;
  EXPECT_NEAR(cx, 0.5, 0.06);
  EXPECT_NEAR(cy, 0.5, 0.06);
  // a figure, not a box: under the bounding box's area, and shaded (many distinct colours)
  EXPECT_LT(b.pixels, 0.85 * (b.x1 - b.x0 + 1) * (b.y1 - b.y0 + 1));
  EXPECT_GT(b.pixels, 0.1 * (b.x1 - b.x0 + 1) * (b.y1 - b.y0 + 1));
  std::set<std::uint32_t> colours;
  for (std::size_t i = 0; i + 2 < im.rgb.size(); i += 3)
    colours.insert(im.rgb[i] << 16 | im.rgb[i + 1] << 8 | im.rgb[i + 2]);
  EXPECT_GT(colours.size(), 200u);
  // the image edges are background
  for (int k = 0; k < 256; ++k) {
    EXPECT_TRUE(is_background(im, k, 0, o.background));
    EXPECT_TRUE(is_background(im, 0, k, o.background));
  }
}

TEST(Thumbnail, LeftSideIsCoolAndRightSideWarm) {
  // seen from the front, the figure's left (+X) is on the image's right
  const auto& m = *fixtures::human48();
  const Image im = decode(server::render_thumbnail(m, core::neutral_configuration(m), plain(256)));
  double cool_x = 0, warm_x = 0;
  int cool = 0, warm = 0;
  for (int y = 0; y < im.height; ++y)
    for (int x = 0; x < im.width; ++x) {
      const std::uint8_t* p = im.at(x, y);
      if (p[2] > p[0] + 40) cool_x += x, ++cool;
      if (p[0] > p[2] + 40) warm_x += x, ++warm;
    }
  ASSERT_GT(cool, 200);
  ASSERT_GT(warm, 200);
  EXPECT_GT(cool_x / cool, warm_x / warm + 10);
}

TEST(Thumbnail, DifferentPosesGiveDifferentImagesAndEqualInputsEqualBytes) {
  const auto& m = *fixtures::human48();
  const auto o = plain(128);
  const Bytes neutral = server::render_thumbnail(m, core::neutral_configuration(m), o);
  const Bytes raised = server::render_thumbnail(m, arm_raised(m), o);
  const Bytes random = server::render_thumbnail(m, core::random_configuration(m, 5), o);
  keep(raised, "human48_arm_raised");
  keep(random, "human48_random");
  EXPECT_EQ(server::render_thumbnail(m, core::neutral_configuration(m), o), neutral);
  const Image a = decode(neutral), b = decode(raised), c = decode(random);
  EXPECT_GT(differing_pixels(a, b), 200);
  EXPECT_GT(differing_pixels(a, c), 500);
  EXPECT_GT(differing_pixels(b, c), 500);
}

TEST(Thumbnail, QuaternionsAreRenormalized) {
  const auto& m = *fixtures::human48();
  const Eigen::VectorXd q = arm_raised(m);
  Eigen::VectorXd scaled = q;
  const int at = m.idx_q[m.joint_index("l_shoulder")];
  scaled.segment<4>(at) *= 3.0;
  const auto o = plain(64);
  EXPECT_EQ(decode(server::render_thumbnail(m, scaled, o)).rgb,
            decode(server::render_thumbnail(m, q, o)).rgb);
}

TEST(Thumbnail, GroundModes) {
  const auto& m = *fixtures::human48();
  const Eigen::VectorXd q = core::neutral_configuration(m);
  server::ThumbnailOptions o;
  o.size = 128;
  const Image none = decode(server::render_thumbnail(m, q, plain(128)));
  o.ground = server::ThumbnailGround::kShadow;
  const Image shadow = decode(server::render_thumbnail(m, q, o));
  o.ground = server::ThumbnailGround::kGridAndShadow;
  const Bytes grid_png = server::render_thumbnail(m, q, o);
  keep(grid_png, "human48_grid");
  const Image grid = decode(grid_png);
  // the shadow darkens the ground under the feet; the grid adds lines beyond the shadow
  const int below_feet = figure_box(none, o.background).y1 + 2;
  ASSERT_LT(below_feet, 128);
  const std::uint8_t* under = shadow.at(64, below_feet);
  EXPECT_LT(under[0], o.background[0]);
  EXPECT_GT(differing_pixels(none, shadow), 100);
  EXPECT_GT(differing_pixels(shadow, grid), 100);
  // far from the figure every mode shows the background
  EXPECT_TRUE(is_background(grid, 0, 0, o.background));
  EXPECT_TRUE(is_background(shadow, 127, 0, o.background));
}

TEST(Thumbnail, BackgroundColourIsUsed) {
  const auto& m = *fixtures::human48();
  auto o = plain(64);
  o.background = {0x10, 0x20, 0x30};
  const Image im = decode(server::render_thumbnail(m, core::neutral_configuration(m), o));
  EXPECT_TRUE(is_background(im, 0, 0, o.background));
  EXPECT_TRUE(is_background(im, 63, 63, o.background));
  EXPECT_FALSE(figure_box(im, o.background).empty());
}

TEST(Thumbnail, LinksWithoutShapesGetBones) {
  // the chain fixture has no geometry at all: joint balls and bones are drawn instead
  const auto m = fixtures::chain(6);
  Eigen::VectorXd q = core::neutral_configuration(*m);
  q.setConstant(0.5);
  const auto o = plain(128);
  const Bytes png = server::render_thumbnail(*m, q, o);
  keep(png, "chain6_bones");
  const Image im = decode(png);
  const Box b = figure_box(im, o.background);
  ASSERT_FALSE(b.empty());
  EXPECT_GT(b.pixels, 150);
}

TEST(Thumbnail, SkinnedMeshIsDrawnInsteadOfTheShapes) {
  PINDRAG_REQUIRE_DATA_DIR();
  const std::string file = fixtures::data_dir() + "/gltf/CesiumMan.glb";
  if (!std::filesystem::exists(file)) GTEST_SKIP() << file << " is absent; skipping";
  const io::SkinnedImport imported = io::import_skinned_file(file);
  ASSERT_FALSE(imported.mesh.empty());
  const core::Model& m = *imported.model;
  const auto o = plain(192);
  const Eigen::VectorXd bind = core::neutral_configuration(m);
  const Bytes skinned = server::render_thumbnail(m, bind, o, &imported.mesh);
  const Bytes shapes = server::render_thumbnail(m, bind, o);
  keep(skinned, "cesium_man_bind");
  const Image a = decode(skinned), b = decode(shapes);
  const Box box = figure_box(a, o.background);
  ASSERT_FALSE(box.empty());
  EXPECT_GT(differing_pixels(a, b), 500);
  const double height = (box.y1 - box.y0 + 1) / 192.0;
  EXPECT_GT(height, 0.6);
  EXPECT_LE(height, 0.81);
  // a frame of its clip moves the skin
  if (!imported.clips.empty() && imported.clips.front().clip.size() > 10) {
    const auto& clip = imported.clips.front().clip;
    const Bytes moved =
        server::render_thumbnail(m, clip.frames[clip.frames.size() / 2], o, &imported.mesh);
    keep(moved, "cesium_man_mid_clip");
    EXPECT_GT(differing_pixels(a, decode(moved)), 200);
  }
}

// a small skin on two links of the chain fixture, valid unless a test breaks it
core::SkinnedMesh tiny_skin() {
  core::SkinnedMesh s;
  s.positions = {{0, 0, 0}, {0.1f, 0, 0}, {0, 0.1f, 0}};
  s.triangles = {{0, 1, 2}};
  s.joints = {{0, 0, 0, 0}, {1, 0, 0, 0}, {0, 1, 0, 0}};
  s.weights = {{1, 0, 0, 0}, {1, 0, 0, 0}, {0.5f, 0.5f, 0, 0}};
  s.bones = {1, 2};
  s.inverse_bind = {core::Transform::Identity(), core::Transform::Identity()};
  return s;
}

template <typename F>
void expect_invalid(F&& f, const std::string& field) {
  try {
    f();
    ADD_FAILURE() << "no exception; expected one naming " << field;
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
  }
}

TEST(Thumbnail, BadInputNamesItsField) {
  const auto& m = *fixtures::human48();
  const Eigen::VectorXd q = core::neutral_configuration(m);
  for (int size : {0, server::kThumbnailMinSize - 1, server::kThumbnailMaxSize + 1, -5}) {
    server::ThumbnailOptions o;
    o.size = size;
    expect_invalid([&] { server::render_thumbnail(m, q, o); }, "options.size");
  }
  const auto o = plain(32);
  expect_invalid([&] { server::render_thumbnail(m, Eigen::VectorXd::Zero(3), o); }, "q: size 3");
  Eigen::VectorXd bad = q;
  bad[bad.size() - 1] = std::numeric_limits<double>::quiet_NaN();
  expect_invalid([&] { server::render_thumbnail(m, bad, o); }, "not finite");
  bad = q;
  bad.segment<4>(m.idx_q[m.joint_index("l_shoulder")]).setZero();
  expect_invalid([&] { server::render_thumbnail(m, bad, o); },
                 "zero quaternion (joint 'l_shoulder')");

  const auto chain = fixtures::chain(3);
  const Eigen::VectorXd qc = core::neutral_configuration(*chain);
  const core::SkinnedMesh good = tiny_skin();
  EXPECT_NO_THROW(server::render_thumbnail(*chain, qc, o, &good));
  auto broken = [&](auto&& change, const std::string& field) {
    core::SkinnedMesh s = tiny_skin();
    change(s);
    expect_invalid([&] { server::render_thumbnail(*chain, qc, o, &s); }, field);
  };
  broken([](core::SkinnedMesh& s) { s.joints[1][0] = 2; }, "skin.joints[1]");
  broken([](core::SkinnedMesh& s) { s.joints[2][3] = -1; }, "skin.joints[2]");
  broken([](core::SkinnedMesh& s) { s.triangles[0][2] = 3; }, "skin.triangles[0]");
  broken([](core::SkinnedMesh& s) { s.weights.pop_back(); }, "skin.weights");
  broken([](core::SkinnedMesh& s) { s.weights[0] = {0, 0, 0, 0}; }, "skin.weights[0]");
  broken([](core::SkinnedMesh& s) { s.weights[1][1] = -0.5f; }, "skin.weights[1]");
  broken([](core::SkinnedMesh& s) { s.positions[2].x() = NAN; }, "skin.positions[2]");
  broken([](core::SkinnedMesh& s) { s.normals = {{0, 0, 1}}; }, "skin.normals");
  broken([](core::SkinnedMesh& s) { s.bones[1] = 7; }, "skin.bones[1]");
  broken([](core::SkinnedMesh& s) { s.inverse_bind.pop_back(); }, "skin.inverse_bind");
  broken([](core::SkinnedMesh& s) { s.inverse_bind[0].p.x() = INFINITY; }, "skin.inverse_bind[0]");
}

TEST(ThumbnailCache, HitsEvictionsAndTheByteCap) {
  const auto& m = *fixtures::human48();
  const auto neutral = core::neutral_configuration(m), raised = arm_raised(m);
  server::ThumbnailCache cache;
  auto o = plain(64);
  o.cache = &cache;
  const Bytes first = server::render_thumbnail(m, neutral, o);
  const Bytes again = server::render_thumbnail(m, neutral, o);
  EXPECT_EQ(first, again);
  auto s = cache.stats();
  EXPECT_EQ(s.misses, 1u);
  EXPECT_EQ(s.hits, 1u);
  EXPECT_EQ(s.entries, 1u);
  EXPECT_EQ(s.bytes, first.size() + server::thumbnail_cache_key(m, neutral, o).size());
  // any change of pose or option is another key
  server::render_thumbnail(m, raised, o);
  auto o2 = o;
  o2.size = 65;
  server::render_thumbnail(m, neutral, o2);
  s = cache.stats();
  EXPECT_EQ(s.misses, 3u);
  EXPECT_EQ(s.entries, 3u);
  EXPECT_NE(server::thumbnail_cache_key(m, neutral, o), server::thumbnail_cache_key(m, raised, o));
  EXPECT_NE(server::thumbnail_cache_key(m, neutral, o),
            server::thumbnail_cache_key(m, neutral, o2));
  EXPECT_NE(server::thumbnail_cache_key(m, neutral, o),
            server::thumbnail_cache_key(
                *core::build_human_figure({.dof = 34}),
                core::neutral_configuration(*core::build_human_figure({.dof = 34})), o));

  // a cap of two entries: the least recently used goes
  const std::size_t entry = first.size() + server::thumbnail_cache_key(m, neutral, o).size();
  server::ThumbnailCache small(2 * entry + entry / 2);
  o.cache = &small;
  server::render_thumbnail(m, neutral, o);  // miss: [neutral]
  server::render_thumbnail(m, raised, o);   // miss: [raised, neutral]
  server::render_thumbnail(m, neutral, o);  // hit:  [neutral, raised]
  const Eigen::VectorXd random = core::random_configuration(m, 3);
  server::render_thumbnail(m, random, o);  // miss, evicts raised: [random, neutral]
  s = small.stats();
  EXPECT_EQ(s.hits, 1u);
  EXPECT_EQ(s.misses, 3u);
  EXPECT_EQ(s.evictions, 1u);
  EXPECT_EQ(s.entries, 2u);
  EXPECT_LE(s.bytes, s.byte_cap);
  EXPECT_NE(small.find(server::thumbnail_cache_key(m, neutral, o)), nullptr);
  EXPECT_EQ(small.find(server::thumbnail_cache_key(m, raised, o)), nullptr);
  // an entry larger than the cap is not stored
  server::ThumbnailCache tiny(16);
  tiny.insert("k", std::make_shared<const Bytes>(Bytes(100, 1)));
  EXPECT_EQ(tiny.stats().entries, 0u);
  EXPECT_EQ(tiny.find("k"), nullptr);
  small.clear();
  EXPECT_EQ(small.stats().entries, 0u);
  EXPECT_EQ(small.stats().bytes, 0u);
}

TEST(ThumbnailCache, ReplacingAKeyKeepsTheByteCountRight) {
  server::ThumbnailCache cache(1000);
  cache.insert("a", std::make_shared<const Bytes>(Bytes(100, 1)));
  cache.insert("a", std::make_shared<const Bytes>(Bytes(300, 2)));
  auto s = cache.stats();
  EXPECT_EQ(s.entries, 1u);
  EXPECT_EQ(s.bytes, 301u);
  EXPECT_EQ(cache.find("a")->size(), 300u);
  // 301 + 3 × 250 > 1000: "a" (least recently used after b, c, d) is evicted
  for (const char* k : {"b", "c", "d"})
    cache.insert(k, std::make_shared<const Bytes>(Bytes(249, 3)));
  s = cache.stats();
  EXPECT_EQ(s.entries, 3u);
  EXPECT_EQ(s.evictions, 1u);
  EXPECT_EQ(s.bytes, 750u);
  EXPECT_EQ(cache.find("a"), nullptr);
}

TEST(Thumbnail, ManyThreadsRenderTheSameImagesAsOne) {
  const auto& m = *fixtures::human48();
  std::vector<Eigen::VectorXd> poses;
  for (std::uint64_t seed = 1; seed <= 6; ++seed)
    poses.push_back(core::random_configuration(m, seed));
  const auto o = plain(96);
  std::vector<Bytes> expected;
  for (const auto& q : poses) expected.push_back(server::render_thumbnail(m, q, o));

  server::ThumbnailCache cache;
  constexpr int kThreads = 6, kRounds = 3;
  std::vector<std::vector<Bytes>> got(kThreads);
  std::vector<std::thread> threads;
  for (int t = 0; t < kThreads; ++t) {
    threads.emplace_back([&, t] {
      for (int r = 0; r < kRounds; ++r) {
        const std::size_t pose = static_cast<std::size_t>(t + r) % poses.size();
        auto opt = o;
        // half of the renders go through one shared cache
        if (t % 2 == 0) opt.cache = &cache;
        got[t].push_back(server::render_thumbnail(m, poses[pose], opt));
      }
    });
  }
  for (auto& th : threads) th.join();
  for (int t = 0; t < kThreads; ++t)
    for (int r = 0; r < kRounds; ++r)
      EXPECT_EQ(got[t][r], expected[static_cast<std::size_t>(t + r) % poses.size()])
          << "thread " << t << " round " << r;
  const auto s = cache.stats();
  EXPECT_EQ(s.hits + s.misses, static_cast<std::uint64_t>(kThreads / 2 * kRounds));
}

TEST(ThumbnailRenderer, NoGlObjectOutlivesARenderAndReleaseFreesAll) {
  const auto& m = *fixtures::human48();
  const Eigen::VectorXd q = core::neutral_configuration(m);
  server::render_thumbnail(m, q, plain(64));
  const auto before = server::thumbnail_renderer_stats();
  ASSERT_TRUE(before.context_alive);
  EXPECT_GT(before.gl_objects, 0);
  EXPECT_EQ(before.samples, 4);
  EXPECT_NE(before.gl_version.find("Core Profile"), std::string::npos) << before.gl_version;
  EXPECT_FALSE(before.gl_renderer.empty());
  // other sizes replace the framebuffers; other poses and skins reuse the buffers
  for (int size : {128, 64, 300, 64}) server::render_thumbnail(m, arm_raised(m), plain(size));
  const auto chain = fixtures::chain(3);
  const core::SkinnedMesh skin = tiny_skin();
  server::render_thumbnail(*chain, core::neutral_configuration(*chain), plain(64), &skin);
  const auto after = server::thumbnail_renderer_stats();
  EXPECT_EQ(after.gl_objects, before.gl_objects);
  EXPECT_EQ(after.renders, before.renders + 5);

  server::release_thumbnail_renderer();
  const auto released = server::thumbnail_renderer_stats();
  EXPECT_FALSE(released.context_alive);
  EXPECT_EQ(released.gl_objects, 0);
  // the next render starts over
  const Image im = decode(server::render_thumbnail(m, q, plain(64)));
  EXPECT_FALSE(figure_box(im, plain(64).background).empty());
  const auto again = server::thumbnail_renderer_stats();
  EXPECT_TRUE(again.context_alive);
  EXPECT_EQ(again.renders, 1u);
  EXPECT_EQ(again.gl_objects, before.gl_objects);
}

}  // namespace
