// asrt bench: a quick, honest measurement of the speed/accuracy presets on this machine. Each
// preset traces a small frame (time, rays/s, steps/ray) whose hit points are compared with a
// Dormand–Prince trace at rtol 1e-13, and four Schwarzschild rays whose deflection is compared with
// Darwin's exact formula. The full study is bench/run (bench/REPORT.md).
#include "Cli.h"

#include "FrameTracer.h"
#include "Measurements.h"
#include "Progress.h"

#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cstdio>

namespace asrt
{
namespace cli
{
namespace
{
const char* const kHelp = R"(Usage: asrt bench [SCENE.json] [options]

Measures, on this machine, what the integrator presets (fast, balanced, accurate) cost and how
accurate they are:
  - time to trace a small frame of the scene (default: the paper's Fig. 1 scene at 64x64),
    best of --repeat runs, rays per second and integration steps per ray;
  - accuracy of that frame: the distance (in M) between each pixel's hit point and the hit of a
    Dormand-Prince trace at rtol 1e-13, median and maximum over the pixels that hit the same object in both,
    and the number of pixels whose hit object changed (they lie on object edges);
  - accuracy against an exact result: the largest relative error of the deflection of
    Schwarzschild rays with impact parameters 5.3, 6, 10 and 100 M, against Darwin's formula.
Times vary with the load of the machine; compare presets within one run. The full benchmark
(every integrator, a 200x200 and a 1920x1080 frame, PostgreSQL) is bench/run, which
regenerates bench/REPORT.md.

Options:
  -r, --resolution WxH  frame size (default 64x64, at most 2048x2048)
  --repeat N            time the best of N traces (default 3)
  -q, --quiet           no progress on stderr
)";

struct Run
{
  double seconds = 1e300;
  double stepsPerRay = 0;
  std::vector<RayRecord> records;
};

Run traceBest(const SceneDescription& scene, const IntegratorConfig& cfg, int repeat,
              const std::string& label, bool quiet)
{
  SceneDescription d = scene;
  d.integrator = cfg;
  const FrameTracer tracer(d);
  Run run;
  tools::ProgressBar bar(label, quiet ? tools::ProgressBar::Style::Silent
                                      : tools::ProgressBar::Style::Automatic);
  for (int k = 0; k < repeat; ++k)
  {
    const auto t0 = std::chrono::steady_clock::now();
    run.records = tracer.traceRows(0, d.camera.height,
                                   [&](double f)
                                   {
                                     bar.update((k + f) / repeat);
                                     return !tools::interruptRequested();
                                   });
    if (tools::interruptRequested())
      throw Interrupted();
    run.seconds = std::min(
      run.seconds, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  }
  bar.finish();
  for (const RayRecord& r : run.records)
    run.stepsPerRay += static_cast<double>(r.steps);
  run.stepsPerRay /= static_cast<double>(run.records.size());
  return run;
}
}

int runBench(const std::vector<std::string>& args)
{
  const Options options(std::vector<OptionSpec>{ { "resolution", OptionSpec::Value, 'r' },
                                                 { "repeat", OptionSpec::Value },
                                                 { "quiet", OptionSpec::Flag, 'q' } },
                        args);
  if (options.help())
  {
    std::printf("%s\n%s", kHelp, kExitCodeHelp);
    return kOk;
  }
  options.expectPositional(0, 1, "");
  const std::string scenePath = options.positional().empty()
                                  ? scenesDirectory() + "/fig1-cylinders.json"
                                  : options.positional()[0];
  const auto size = options.size("resolution").value_or(std::make_pair(64, 64));
  // Two frames' records are held at once (the reference and a run), with no memory check.
  constexpr long long kMaxBenchPixels = 1LL << 22;
  if (static_cast<long long>(size.first) * size.second > kMaxBenchPixels)
    throw UsageError("--resolution: at most " + std::to_string(kMaxBenchPixels) +
                     " pixels (2048x2048) for a benchmark, got " + options.get("resolution"));
  const int repeat = options.positiveInteger("repeat").value_or(3);
  const bool quiet = options.has("quiet");

  SceneDescription scene = loadSceneFile(scenePath, tools::vtkImageLoader());
  scene.camera.width = size.first;
  scene.camera.height = size.second;
  std::printf("asrt bench: %s (%s) at %dx%d, %d OpenMP threads, best of %d\n\n", scenePath.c_str(),
              scene.name.c_str(), size.first, size.second, omp_get_max_threads(), repeat);

  IntegratorConfig tight = integratorPreset("accurate");
  // The reference is the general method, so that it checks the fast paths "auto" picks rather than
  // repeating them.
  tight.method = "DormandPrince54";
  tight.relativeTolerance = 1e-13;
  tight.absoluteTolerance = 1e-15;
  const Run reference = traceBest(scene, tight, 1, "bench reference", quiet);

  std::printf("%-9s %-16s %7s %9s %9s %9s %12s %12s %8s %14s\n", "preset", "method", "rtol",
              "time (s)", "rays/s", "steps/ray", "hit err med", "hit err max", "changed",
              "deflection err");
  const std::vector<double> impacts = { 5.3, 6.0, 10.0, 100.0 };
  for (const char* preset : { "fast", "balanced", "accurate" })
  {
    IntegratorConfig cfg = integratorPreset(preset);
    const Run run = traceBest(scene, cfg, repeat, std::string("bench ") + preset, quiet);
    std::vector<double> errors;
    int changed = 0;
    for (std::size_t k = 0; k < run.records.size(); ++k)
    {
      const RayRecord &a = run.records[k], &b = reference.records[k];
      if (a.objectId != b.objectId || a.termination != b.termination)
        ++changed;
      else if (a.objectId >= 0)
        errors.push_back((a.hitPoint - b.hitPoint).norm());
    }
    std::sort(errors.begin(), errors.end());
    double deflectionError = 0;
    for (double b : impacts)
      deflectionError =
        std::max(deflectionError, tools::schwarzschildDeflection(cfg, b).relativeError());
    const std::string method =
      cfg.method == "auto" ? defaultMethod(*makeSpacetime(scene.spacetime)) : cfg.method;
    std::printf("%-9s %-16s %7.0e %9.3f %9.0f %9.0f %12.1e %12.1e %8d %14.1e\n", preset,
                method.c_str(), cfg.relativeTolerance, run.seconds,
                run.records.size() / run.seconds, run.stepsPerRay,
                errors.empty() ? 0.0 : errors[errors.size() / 2],
                errors.empty() ? 0.0 : errors.back(), changed, deflectionError);
  }
  std::printf("\nhit err: distance in M to the hit of a Dormand-Prince trace at rtol 1e-13 (%.2f "
              "s), over pixels "
              "hitting the same object;\nchanged: pixels whose hit object differs (object edges); "
              "deflection err: max relative error\nagainst Darwin's exact deflection for b = 5.3, "
              "6, 10, 100 M. Full study: bench/run -> bench/REPORT.md.\n",
              reference.seconds);
  return kOk;
}
}
}
