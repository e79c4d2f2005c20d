// Tests for `pindrag thumbnail` (cli/cmd_thumbnail.cpp), run as a process: exit codes, the PNG
// written (decoded with libpng), frames of a BVH clip, and bad files, frames and sizes refused
// with a message.
#include <gtest/gtest.h>
#include <png.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "tests/fixtures/fixtures.hpp"

namespace {

namespace fs = std::filesystem;

struct CommandResult {
  int exit_code = -1;
  std::string output;  // stdout and stderr
};

CommandResult run_thumbnail(const std::string& args) {
  const std::string command = std::string(PINDRAG_EXE) + " thumbnail " + args + " 2>&1";
  CommandResult r;
  FILE* pipe = ::popen(command.c_str(), "r");
  if (pipe == nullptr) return r;
  std::array<char, 4096> chunk{};
  while (std::fgets(chunk.data(), chunk.size(), pipe) != nullptr) r.output += chunk.data();
  const int status = ::pclose(pipe);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

fs::path scratch(const std::string& name) {
  const fs::path dir =
      fs::temp_directory_path() / ("pindrag_thumbnail_cli_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  return dir / name;
}

// width, height and RGB pixels of a PNG file, read by libpng; width 0 when unreadable
struct Decoded {
  int width = 0, height = 0;
  std::vector<std::uint8_t> rgb;
};
Decoded read_png(const fs::path& path) {
  png_image image{};
  image.version = PNG_IMAGE_VERSION;
  Decoded d;
  if (!png_image_begin_read_from_file(&image, path.c_str())) return d;
  image.format = PNG_FORMAT_RGB;
  d.rgb.resize(PNG_IMAGE_SIZE(image));
  if (!png_image_finish_read(&image, nullptr, d.rgb.data(), 0, nullptr)) return d;
  d.width = static_cast<int>(image.width);
  d.height = static_cast<int>(image.height);
  return d;
}

TEST(ThumbnailCommand, RendersABundledCharacter) {
  const fs::path out = scratch("human48.png");
  fs::remove(out);
  const CommandResult r = run_thumbnail("human48 -o " + out.string() + " --size 96");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("wrote"), std::string::npos) << r.output;
  const Decoded d = read_png(out);
  EXPECT_EQ(d.width, 96);
  EXPECT_EQ(d.height, 96);
}

TEST(ThumbnailCommand, FramesOfABvhClipDiffer) {
  PINDRAG_REQUIRE_DATA_DIR();
  const std::string bvh = fixtures::data_dir() + "/bvh/cmu_01_01_jumps.bvh";
  if (!fs::exists(bvh)) GTEST_SKIP() << bvh << " is absent; skipping";
  const fs::path first = scratch("jump0.png"), later = scratch("jump200.png");
  ASSERT_EQ(run_thumbnail(bvh + " -o " + first.string() + " --size 64").exit_code, 0);
  const CommandResult r = run_thumbnail(bvh + " -o " + later.string() + " --frame 200 --size 64");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const Decoded a = read_png(first), b = read_png(later);
  ASSERT_EQ(a.width, 64);
  ASSERT_EQ(b.width, 64);
  EXPECT_NE(a.rgb, b.rgb);
  // a frame past the end names the frame count
  const CommandResult past = run_thumbnail(bvh + " -o " + later.string() + " --frame 100000");
  EXPECT_NE(past.exit_code, 0);
  EXPECT_NE(past.output.find("--frame 100000"), std::string::npos) << past.output;
  EXPECT_NE(past.output.find("frames"), std::string::npos) << past.output;
}

TEST(ThumbnailCommand, BadInputsFailWithAMessage) {
  const fs::path out = scratch("bad.png");
  fs::remove(out);
  // a file that does not exist
  CommandResult r = run_thumbnail("/nonexistent/figure.urdf -o " + out.string());
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("pindrag thumbnail:"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("/nonexistent/figure.urdf"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(out));
  // a malformed BVH
  const fs::path broken = scratch("broken.bvh");
  std::ofstream(broken) << "HIERARCHY\nROOT hips\n{\n  OFFSET 0 0\n";
  r = run_thumbnail(broken.string() + " -o " + out.string());
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find(broken.string()), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(out));
  // a size outside the range, a frame of a character without motion, an unwritable output
  r = run_thumbnail("human48 -o " + out.string() + " --size 5000");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("--size"), std::string::npos) << r.output;
  r = run_thumbnail("human48 -o " + out.string() + " --frame 3");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("no motion"), std::string::npos) << r.output;
  r = run_thumbnail("human48 -o /nonexistent/dir/out.png --size 16");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("/nonexistent/dir/out.png"), std::string::npos) << r.output;
  // no output named
  r = run_thumbnail("human48");
  EXPECT_NE(r.exit_code, 0);
}

}  // namespace
