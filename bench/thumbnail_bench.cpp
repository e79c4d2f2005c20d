// Thumbnails (server/thumbnail.hpp) of the human48 figure: a whole render by size, its CPU parts
// (scene building, PNG encoding) alone, a cache hit, and renders from several threads at once.
#include <benchmark/benchmark.h>

#include <thread>
#include <vector>

#include "core/configuration.hpp"
#include "core/human_figure.hpp"
#include "server/png_encode.hpp"
#include "server/thumbnail.hpp"
#include "server/thumbnail_renderer.hpp"
#include "server/thumbnail_scene.hpp"

namespace {

const core::Model& human48() {
  static const auto model = core::build_human_figure({});
  return *model;
}

// distinct poses, so that nothing is answered from a cache
const std::vector<Eigen::VectorXd>& poses() {
  static const std::vector<Eigen::VectorXd> q = [] {
    std::vector<Eigen::VectorXd> out;
    for (std::uint64_t seed = 1; seed <= 16; ++seed)
      out.push_back(core::random_configuration(human48(), seed));
    return out;
  }();
  return q;
}

void BM_Thumbnail_Render(benchmark::State& state) {
  server::ThumbnailOptions o;
  o.size = static_cast<int>(state.range(0));
  std::size_t i = 0, bytes = 0;
  server::render_thumbnail(human48(), poses()[0], o);  // context, programs, shader JIT
  for (auto _ : state) {
    const auto png = server::render_thumbnail(human48(), poses()[i++ % poses().size()], o);
    bytes += png.size();
  }
  state.counters["png_bytes"] =
      static_cast<double>(bytes) / static_cast<double>(state.iterations());
}
BENCHMARK(BM_Thumbnail_Render)
    ->Arg(64)
    ->Arg(128)
    ->Arg(256)
    ->Arg(512)
    ->Unit(benchmark::kMillisecond);

void BM_Thumbnail_Scene(benchmark::State& state) {
  server::ThumbnailOptions o;
  o.size = static_cast<int>(state.range(0));
  std::size_t i = 0;
  for (auto _ : state) {
    auto scene =
        server::build_thumbnail_scene(human48(), poses()[i++ % poses().size()], o, nullptr);
    benchmark::DoNotOptimize(scene.figure.vertices.data());
  }
}
BENCHMARK(BM_Thumbnail_Scene)->Arg(256)->Unit(benchmark::kMillisecond);

void BM_Thumbnail_Draw(benchmark::State& state) {
  server::ThumbnailOptions o;
  o.size = static_cast<int>(state.range(0));
  const auto scene = server::build_thumbnail_scene(human48(), poses()[0], o, nullptr);
  server::draw_thumbnail_scene(scene);
  for (auto _ : state) benchmark::DoNotOptimize(server::draw_thumbnail_scene(scene).data());
}
BENCHMARK(BM_Thumbnail_Draw)->Arg(256)->Unit(benchmark::kMillisecond);

void BM_Thumbnail_Png(benchmark::State& state) {
  server::ThumbnailOptions o;
  o.size = static_cast<int>(state.range(0));
  const auto rgb = server::draw_thumbnail_scene(
      server::build_thumbnail_scene(human48(), poses()[0], o, nullptr));
  for (auto _ : state) benchmark::DoNotOptimize(server::encode_png_rgb(rgb, o.size, o.size).data());
}
BENCHMARK(BM_Thumbnail_Png)->Arg(256)->Unit(benchmark::kMillisecond);

void BM_Thumbnail_CacheHit(benchmark::State& state) {
  server::ThumbnailCache cache;
  server::ThumbnailOptions o;
  o.size = 256;
  o.cache = &cache;
  server::render_thumbnail(human48(), poses()[0], o);
  for (auto _ : state)
    benchmark::DoNotOptimize(server::render_thumbnail(human48(), poses()[0], o).data());
}
BENCHMARK(BM_Thumbnail_CacheHit)->Unit(benchmark::kMicrosecond);

// renders per second with N threads rendering at once (the GL part is serialized)
void BM_Thumbnail_Threads(benchmark::State& state) {
  const int threads = static_cast<int>(state.range(0));
  constexpr int kPerThread = 8;
  server::ThumbnailOptions o;
  o.size = 256;
  server::render_thumbnail(human48(), poses()[0], o);
  for (auto _ : state) {
    std::vector<std::thread> pool;
    for (int t = 0; t < threads; ++t)
      pool.emplace_back([&, t] {
        for (int k = 0; k < kPerThread; ++k)
          server::render_thumbnail(
              human48(), poses()[static_cast<std::size_t>(t * kPerThread + k) % poses().size()], o);
      });
    for (auto& th : pool) th.join();
  }
  state.counters["renders_per_s"] = benchmark::Counter(
      static_cast<double>(state.iterations()) * threads * kPerThread, benchmark::Counter::kIsRate);
}
BENCHMARK(BM_Thumbnail_Threads)
    ->Arg(1)
    ->Arg(2)
    ->Arg(4)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
