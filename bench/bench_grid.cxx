// The adaptive ray grid (AdaptiveGrid.h) against tracing every pixel: every scene at 200×200,
// 800×450 and 1920×1080, each preset traced whole without the grid and with it, in the same run.
// Each frame is scored against the full trace of the same settings (whole frame) and against a
// converged picture (N×N point samples a pixel) on a regular sample of pixels, which the benchmark
// traces itself. Prints a Markdown section for bench/REPORT.md.
// Usage: asrt_bench_grid SCENE.json... [--grid L[:TOLERANCE]]... [--no-hd] [--only-size WIDTH]
#include "FrameTracer.h"
#include "GeodesicSceneLoading.h"
#include "ImageQuality.h"
#include "SceneFile.h"

#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <string>
#include <vector>

using namespace asrt;

namespace
{
/// The grid meets a preset's accuracy when its frame is within this of the full trace...
constexpr double kGoalPsnrAgainstFull = 40.0;
/// ...and its score against the converged picture at most this below the full trace's.
constexpr double kGoalConvergedLoss = 0.2;

double now()
{
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

double cpuNow()
{
  timespec t;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

double loadAverage()
{
  double load[1] = { 0 };
  return getloadavg(load, 1) == 1 ? load[0] : -1.0;
}

std::uint8_t level(double c)
{
  return static_cast<std::uint8_t>(std::lround(255.0 * std::clamp(c, 0.0, 1.0)));
}

/// A traced frame, as its PNG would store it, with what it cost.
struct Frame
{
  std::vector<RayRecord> records;
  std::vector<std::uint8_t> rgb;
  double seconds = 0, cpu = 0;
  long long rays = 0, centres = 0, steps = 0;
};

Frame trace(const SceneDescription& d, const std::vector<std::pair<int, int>>* pixels = nullptr)
{
  FrameTracer tracer(d);
  Frame f;
  const double t0 = now(), c0 = cpuNow();
  f.records = pixels ? tracer.tracePixels(*pixels) : tracer.traceRows(0, d.camera.height);
  f.seconds = now() - t0;
  f.cpu = cpuNow() - c0;
  f.rgb.resize(3 * f.records.size());
  for (std::size_t k = 0; k < f.records.size(); ++k)
  {
    const RayRecord& r = f.records[k];
    f.rays += r.raysPerPixel;
    f.centres += r.traced ? 1 : 0;
    f.steps += r.steps;
    for (int c = 0; c < 3; ++c)
      f.rgb[3 * k + c] = level(r.color[c]);
  }
  return f;
}

/// The frame's colours at the sampled pixels, as an image of sample.size() × 1.
std::vector<std::uint8_t> sampled(const Frame& f, const std::vector<std::pair<int, int>>& sample,
                                  int W)
{
  std::vector<std::uint8_t> out;
  out.reserve(3 * sample.size());
  for (const auto& [i, j] : sample)
    for (int c = 0; c < 3; ++c)
      out.push_back(f.rgb[3 * (static_cast<std::size_t>(j) * W + i) + c]);
  return out;
}

double psnrOf(const std::vector<std::uint8_t>& a, const std::vector<std::uint8_t>& b)
{
  const int n = static_cast<int>(a.size() / 3);
  return psnr(RgbView{ n, 1, a.data() }, RgbView{ n, 1, b.data() });
}

std::string db(double v)
{
  char s[32];
  if (std::isinf(v))
    return "∞";
  std::snprintf(s, sizeof s, "%.1f", v);
  return s;
}

/// Pixels whose object, image order or ending differ between the frames; in `offEdge` those whose
/// 3×3 neighbourhood in the full frame holds no other object, order or ending.
int changedPixels(const Frame& grid, const Frame& full, int W, int H, int& offEdge)
{
  auto same = [](const RayRecord& a, const RayRecord& b)
  {
    return a.objectId == b.objectId && a.imageOrder == b.imageOrder &&
           a.termination == b.termination;
  };
  int changed = 0;
  offEdge = 0;
  for (int j = 0; j < H; ++j)
    for (int i = 0; i < W; ++i)
    {
      const std::size_t k = static_cast<std::size_t>(j) * W + i;
      if (same(grid.records[k], full.records[k]))
        continue;
      ++changed;
      bool edge = false;
      for (int dj = -1; dj <= 1 && !edge; ++dj)
        for (int di = -1; di <= 1 && !edge; ++di)
        {
          const int a = i + di, b = j + dj;
          if (a >= 0 && b >= 0 && a < W && b < H)
            edge = !same(full.records[static_cast<std::size_t>(b) * W + a], full.records[k]);
        }
      if (!edge)
      {
        ++offEdge;
        if (std::getenv("ASRT_BENCH_GRID_DIAG"))
        {
          const RayRecord &f = full.records[k], &g = grid.records[k];
          std::fprintf(
            stderr,
            "    off-edge change at (%d, %d): full %d/%d winding %.3f, grid %d/%d traced %d\n", i,
            j, f.objectId, f.imageOrder, f.winding, g.objectId, g.imageOrder, int(g.traced));
        }
      }
    }
  return changed;
}

/// A lattice step and a tolerance of the grid.
struct GridChoice
{
  int lattice = 16;
  double tolerance = 1e-3;
};

struct Size
{
  int width, height, stride, referenceSide;
};

/// One scene at one size: the converged reference at the sampled pixels, then each preset without
/// and with the grid, each table row one preset and lattice. Clears met[g] where grid choice g
/// missed a goal.
void sceneAtSize(const SceneDescription& base, const std::string& file, const Size& size,
                 const std::vector<std::string>& presets, const std::vector<GridChoice>& grids,
                 std::vector<bool>& met)
{
  SceneDescription scene = base;
  scene.camera.width = size.width;
  scene.camera.height = size.height;
  const int W = size.width, H = size.height;
  std::vector<std::pair<int, int>> sample;
  for (int j = size.stride / 2; j < H; j += size.stride)
    for (int i = size.stride / 2; i < W; i += size.stride)
      sample.emplace_back(i, j);

  std::fprintf(stderr, "%s at %dx%d: reference...\n", file.c_str(), W, H);
  SceneDescription refScene = scene;
  refScene.integrator = integratorPreset("accurate");
  refScene.rendering = singleRayRendering();
  refScene.rendering.supersample = size.referenceSide;
  const Frame ref = trace(refScene, &sample);
  std::vector<std::uint8_t> refRgb = ref.rgb;

  std::printf("\n#### `%s` at %d×%d\n\n", file.c_str(), W, H);
  std::printf("Converged picture: %d×%d point samples a pixel, accurate integrator, at the %zu "
              "pixels of every %dth row and column (%.1f s).\n\n",
              size.referenceSide, size.referenceSide, sample.size(), size.stride, ref.seconds);
  std::printf("| preset | grid (lattice, tolerance) | centre rays traced | rays | steps | wall "
              "time | CPU time | PSNR "
              "against the full trace | against converged (full trace's) | changed (off an edge) "
              "| meets the goals |\n|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (const std::string& preset : presets)
  {
    SceneDescription d = scene;
    d.integrator = integratorPreset(preset);
    d.rendering = renderingPreset(preset);
    d.rendering.gridLattice = 1;
    std::fprintf(stderr, "  %s, every pixel...\n", preset.c_str());
    const Frame full = trace(d);
    const double fullScore = psnrOf(sampled(full, sample, W), refRgb);
    const double pixels = static_cast<double>(W) * H;
    std::printf("| %s | off | 100 %% | %lld | %lld | %.2f s | %.2f s | — | %s dB | — | — |\n",
                preset.c_str(), full.rays, full.steps, full.seconds, full.cpu,
                db(fullScore).c_str());
    for (std::size_t c = 0; c < grids.size(); ++c)
    {
      const GridChoice& g = grids[c];
      d.rendering.gridLattice = g.lattice;
      d.rendering.gridTolerance = g.tolerance;
      std::fprintf(stderr, "  %s, grid %d, tolerance %g...\n", preset.c_str(), g.lattice,
                   g.tolerance);
      const Frame grid = trace(d);
      const double againstFull =
        psnr(RgbView{ W, H, grid.rgb.data() }, RgbView{ W, H, full.rgb.data() });
      const double score = psnrOf(sampled(grid, sample, W), refRgb);
      int offEdge = 0;
      const int changed = changedPixels(grid, full, W, H, offEdge);
      const bool ok = againstFull >= kGoalPsnrAgainstFull &&
                      score >= fullScore - kGoalConvergedLoss && offEdge == 0;
      if (!ok)
        met[c] = false;
      std::printf("| %s | %d, %g | %.1f %% | %lld (%.2f×) | %lld (%.2f×) | %.2f s (%.2f×) | %.2f s "
                  "(%.2f×) | %s dB | %s dB (%s) | %d (%d) | %s |\n",
                  preset.c_str(), g.lattice, g.tolerance, 100.0 * grid.centres / pixels, grid.rays,
                  static_cast<double>(grid.rays) / full.rays, grid.steps,
                  static_cast<double>(grid.steps) / full.steps, grid.seconds,
                  grid.seconds / full.seconds, grid.cpu, grid.cpu / full.cpu,
                  db(againstFull).c_str(), db(score).c_str(), db(fullScore).c_str(), changed,
                  offEdge, ok ? "**yes**" : "no");
    }
  }
}
}

int main(int argc, char* argv[])
{
  std::vector<std::string> files;
  std::vector<GridChoice> grids;
  std::vector<Size> sizes = { { 200, 200, 2, 8 }, { 800, 450, 4, 6 }, { 1920, 1080, 8, 4 } };
  for (int k = 1; k < argc; ++k)
  {
    if (std::strcmp(argv[k], "--grid") == 0 && k + 1 < argc)
    {
      // L or L:TOLERANCE
      GridChoice g;
      g.lattice = std::atoi(argv[++k]);
      if (const char* colon = std::strchr(argv[k], ':'))
        g.tolerance = std::atof(colon + 1);
      grids.push_back(g);
    }
    else if (std::strcmp(argv[k], "--only-size") == 0 && k + 1 < argc)
    {
      const int w = std::atoi(argv[++k]);
      sizes.erase(
        std::remove_if(sizes.begin(), sizes.end(), [w](const Size& s) { return s.width != w; }),
        sizes.end());
    }
    else if (std::strcmp(argv[k], "--no-hd") == 0)
      sizes.pop_back();
    else
      files.emplace_back(argv[k]);
  }
  if (files.empty())
  {
    std::fprintf(
      stderr, "usage: %s SCENE.json... [--grid L[:TOLERANCE]]... [--no-hd] [--only-size WIDTH]\n",
      argv[0]);
    return 2;
  }
  if (grids.empty())
    grids = { GridChoice{ 8, 3e-4 }, GridChoice{ 16, 3e-4 } };
  const std::vector<std::string> presets = { "fast", "balanced" };
  const double start = now();
  std::printf("<!-- grid:begin -->\n## The adaptive ray grid against tracing every pixel\n\n");
  std::printf(
    "Command: `asrt_bench_grid` on every scene of `Data/scenes` (`ASRT_BENCH_ONLY=grid bench/run` "
    "runs it), %d OpenMP threads. Each preset's frame is traced whole (`FrameTracer::traceRows`, "
    "no output) without the grid and with it, once each, one after the other. *Centre rays "
    "traced*: the share of pixels whose own ray was traced (`RayRecord::traced`); *rays*: the "
    "sum of `raysPerPixel` (centre, anti-aliasing and edge-midpoint rays); *steps*: the centre "
    "rays' integration steps; in brackets, against the full trace. PSNR of the 8-bit colours "
    "against the full trace (whole frame) and against the converged picture (the sampled "
    "pixels; in brackets the full trace's own score there). *Changed*: pixels whose object, image "
    "order or ending differ from the full trace's; in brackets those with no other in their "
    "3×3 neighbourhood of the full trace (off an edge). Goals: ≥ %.0f dB against the full "
    "trace, at most %.1f dB below its score against the converged picture, no pixel changed off "
    "an edge.\n",
    omp_get_max_threads(), kGoalPsnrAgainstFull, kGoalConvergedLoss);
  std::vector<bool> met(grids.size(), true);
  for (const Size& size : sizes)
  {
    std::printf("\n### At %d×%d\n", size.width, size.height);
    for (const std::string& file : files)
    {
      const SceneDescription scene = loadSceneFile(file, vtkImageFileLoader());
      sceneAtSize(scene, file, size, presets, grids, met);
    }
  }
  std::printf("\n");
  for (std::size_t c = 0; c < grids.size(); ++c)
    std::printf("Lattice %d, tolerance %g: %s.\n", grids[c].lattice, grids[c].tolerance,
                met[c] ? "every row meets the goals" : "some row misses a goal");
  std::printf("\nThe run took %.0f s; load average (1 min) at its end %.1f on %d cores.\n",
              now() - start, loadAverage(), omp_get_num_procs());
  std::printf("<!-- grid:end -->\n");
  return 0;
}
