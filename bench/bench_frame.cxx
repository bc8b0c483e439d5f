// Frame tracing: speed against accuracy on whole frames. The paper's Fig. 1 scene at 200×200 with
// every method worth comparing, against a tight general-method reference traced here; then Fig. 1
// and the Kerr disk at 1920×1080, the current default against the previous one in the same run,
// their accuracy checked on a regular sample of pixels against the same kind of reference. Prints a
// Markdown section for bench/REPORT.md.
// Usage: asrt_bench_frame fig1.json kerr-disk.json [--no-hd]
#include "FrameTracer.h"
#include "GeodesicSceneLoading.h"
#include "SceneFile.h"

#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <string>
#include <vector>

using namespace asrt;

namespace
{
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

struct Config
{
  std::string label;
  IntegratorConfig integrator;
  bool farField = true;
};

struct Run
{
  Config config;
  double seconds = 0, cpu = 0, steps = 0;
  std::vector<RayRecord> records;
};

IntegratorConfig method(const std::string& name, double rtol, double step = 0.05)
{
  IntegratorConfig c;
  c.method = name;
  c.relativeTolerance = rtol;
  c.absoluteTolerance = 1e-2 * rtol;
  c.step = step;
  return c;
}

/// Best wall time of `repetitions` whole-frame traces, with the CPU time of that repetition.
Run trace(const SceneDescription& base, const Config& cfg, int repetitions,
          const std::vector<std::pair<int, int>>* pixels = nullptr)
{
  SceneDescription d = base;
  d.integrator = cfg.integrator;
  FrameTracer tracer(d);
  tracer.setFarField(cfg.farField);
  Run r;
  r.config = cfg;
  r.seconds = 1e300;
  for (int rep = 0; rep < repetitions; ++rep)
  {
    const double t0 = now(), c0 = cpuNow();
    r.records = pixels ? tracer.tracePixels(*pixels) : tracer.traceRows(0, d.camera.height);
    const double t = now() - t0;
    if (t < r.seconds)
    {
      r.seconds = t;
      r.cpu = cpuNow() - c0;
    }
  }
  for (const RayRecord& rec : r.records)
    r.steps += static_cast<double>(rec.steps);
  r.steps /= static_cast<double>(r.records.size());
  return r;
}

struct Accuracy
{
  double maxError = 0, p99 = 0;
  int differ = 0;        ///< pixels whose object or termination differs from the reference's
  int differOffEdge = 0; ///< of those, pixels with no other object or ending in their 3×3 block
};

/// Errors of `records` (pixel k at `where[k]`) against `reference` at the same pixels. `frame` is
/// the whole frame of the tested run, width W, for judging whether a pixel lies at an edge.
Accuracy compare(const std::vector<RayRecord>& records, const std::vector<RayRecord>& reference,
                 const std::vector<RayRecord>& frame, int W, int H)
{
  Accuracy a;
  std::vector<double> errors;
  for (std::size_t k = 0; k < records.size(); ++k)
  {
    const RayRecord &x = records[k], &y = reference[k];
    if (x.objectId != y.objectId || x.termination != y.termination)
    {
      ++a.differ;
      bool edge = false;
      for (int dj = -1; dj <= 1 && !edge; ++dj)
        for (int di = -1; di <= 1 && !edge; ++di)
        {
          const int i = x.i + di, j = x.j + dj;
          if (i < 0 || j < 0 || i >= W || j >= H)
            continue;
          const RayRecord& n = frame[static_cast<std::size_t>(j) * W + i];
          edge = n.objectId != x.objectId || n.termination != x.termination;
        }
      if (!edge)
        ++a.differOffEdge;
      continue;
    }
    if (x.objectId >= 0)
      errors.push_back((x.hitPoint - y.hitPoint).norm());
  }
  std::sort(errors.begin(), errors.end());
  if (!errors.empty())
  {
    a.maxError = errors.back();
    a.p99 = errors[static_cast<std::size_t>(0.99 * static_cast<double>(errors.size() - 1))];
  }
  return a;
}

void printRow(const Run& r, const Accuracy& a, int threads)
{
  const double n = static_cast<double>(r.records.size());
  std::printf("| %s | %.3f s | %.0f | %.0f | %.0f | %.1e | %.1e | %d (%d) |\n",
              r.config.label.c_str(), r.seconds, n / r.seconds, 1e9 * r.cpu / n, r.steps,
              a.maxError, a.p99, a.differ, a.differOffEdge);
  (void)threads;
}

const char* tableHead = "| configuration | wall time | rays/s | CPU ns/ray | steps/ray | max hit "
                        "error (M) | 99th pct (M) | differ (off an edge) |\n"
                        "|---|---|---|---|---|---|---|---|\n";

/// The 200×200 Fig. 1 table: every configuration on every pixel against the reference.
void smallFrame(const SceneDescription& scene, const char* file)
{
  const int W = scene.camera.width, H = scene.camera.height;
  const Run reference =
    trace(scene, { "reference: DormandPrince54 rtol 1e-13", method("DormandPrince54", 1e-13) }, 1);
  std::vector<Config> configs = {
    { "**auto, balanced (the default)**", integratorPreset("balanced") },
    { "auto, fast", integratorPreset("fast") },
    { "auto, accurate", integratorPreset("accurate") },
    { "PlanarOrbit rtol 1e-9, far field off", method("PlanarOrbit", 1e-9), false },
    { "DormandPrince54 rtol 1e-6 (the former fast)", method("DormandPrince54", 1e-6) },
    { "DormandPrince54 rtol 1e-8 (the former default)", method("DormandPrince54", 1e-8) },
    { "DormandPrince54 rtol 1e-10 (the former accurate)", method("DormandPrince54", 1e-10) },
    { "SchwarzschildSplit4 h = 0.005", method("SchwarzschildSplit4", 1e-8, 0.005) },
    { "GaussLegendre6 h = 0.1", method("GaussLegendre6", 1e-8, 0.1) },
  };
  for (double rtol : { 1e-7, 1e-8, 1e-9, 1e-10, 1e-11 })
  {
    char label[64];
    std::snprintf(label, sizeof label, "PlanarOrbit rtol %.0e", rtol);
    configs.push_back({ label, method("PlanarOrbit", rtol) });
  }
  std::printf("### Fig. 1 at %d×%d, every configuration\n\n", W, H);
  std::printf(
    "Scene `%s` (%s), %d OpenMP threads. Wall time: best of three whole-frame traces "
    "(`FrameTracer::traceRows`, no output); CPU time of that repetition over all "
    "threads. Hit error: the distance between a pixel's hit point and the reference's "
    "(%s, %.0f steps a ray, %.2f s), over pixels hitting the same object; *differ* counts "
    "pixels whose hit object or ending changed, and in brackets those of them with no "
    "other object or ending in their 3×3 neighbourhood (off an object's edge). Steps per "
    "ray are segments handed to the object tests, the whole way to the sky.\n\n",
    file, scene.name.c_str(), omp_get_max_threads(), reference.config.label.c_str(),
    reference.steps, reference.seconds);
  std::printf("%s", tableHead);
  const char* only = std::getenv("ASRT_BENCH_FRAME_ONLY");
  for (const Config& c : configs)
  {
    if (only && c.label.find(only) == std::string::npos)
      continue;
    const Run r = trace(scene, c, 3);
    printRow(r, compare(r.records, reference.records, r.records, W, H), omp_get_max_threads());
  }
}

/// A 1920×1080 frame: default and former default, whole frames timed, accuracy on every
/// `stride`-th pixel in both directions against the reference traced at those pixels only.
void hdFrame(const SceneDescription& base, const char* file, const std::vector<Config>& configs,
             int stride)
{
  SceneDescription scene = base;
  scene.camera.width = 1920;
  scene.camera.height = 1080;
  const int W = scene.camera.width, H = scene.camera.height;
  std::vector<std::pair<int, int>> sample;
  for (int j = stride / 2; j < H; j += stride)
    for (int i = stride / 2; i < W; i += stride)
      sample.emplace_back(i, j);
  const Run reference = trace(
    scene, { "DormandPrince54 rtol 1e-13", method("DormandPrince54", 1e-13), false }, 1, &sample);
  std::printf("\n### `%s` at 1920×1080\n\n", file);
  std::printf("%s (%s). Whole frames, best of two; accuracy on the %zu pixels of every %dth row "
              "and column, against %s traced at those pixels (%.0f steps a ray).\n\n",
              scene.name.c_str(), file, sample.size(), stride, reference.config.label.c_str(),
              reference.steps);
  std::printf("%s", tableHead);
  for (const Config& c : configs)
  {
    const Run r = trace(scene, c, 2);
    std::vector<RayRecord> sampled;
    sampled.reserve(sample.size());
    for (const auto& [i, j] : sample)
      sampled.push_back(r.records[static_cast<std::size_t>(j) * W + i]);
    Run shown = r;
    printRow(shown, compare(sampled, reference.records, r.records, W, H), omp_get_max_threads());
  }
}
}

int main(int argc, char* argv[])
{
  if (argc < 3)
  {
    std::fprintf(stderr, "usage: %s fig1.json kerr-disk.json [--no-hd]\n", argv[0]);
    return 2;
  }
  const bool hd = !(argc > 3 && std::strcmp(argv[3], "--no-hd") == 0);
  const SceneDescription fig1 = loadSceneFile(argv[1], vtkImageFileLoader());
  const SceneDescription kerr = loadSceneFile(argv[2], vtkImageFileLoader());
  std::printf("<!-- frame:begin -->\n## Frame tracing: speed against accuracy on whole frames\n\n");
  smallFrame(fig1, argv[1]);
  if (hd)
  {
    hdFrame(
      fig1, argv[1],
      { { "**auto, balanced (the default)**", integratorPreset("balanced") },
        { "DormandPrince54 rtol 1e-8 (the former default)", method("DormandPrince54", 1e-8) } },
      8);
    hdFrame(kerr, argv[2],
            { { "**auto, balanced (the default)**", integratorPreset("balanced") },
              { "KerrMino4 h = 0.05 (the former default)", method("KerrMino4", 1e-8, 0.05) } },
            8);
  }
  std::printf("<!-- frame:end -->\n");
  return 0;
}
