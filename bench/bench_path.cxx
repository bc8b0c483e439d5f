// Per-pixel interpolation along a movie path (PathInterpolation.h) on the mass ramp of Figs. 4–5 at
// 200×200: for key spacings h, frames between keys made plain and to quality targets, each scored
// against the converged picture of its view (8×8 point samples a pixel, traced here) and against
// the frame traced at its parameters with the same settings; the estimate's rank correlation with
// the true error; the re-trace share it needs for 35 and 40 dB against an oracle's (true error
// first); and the cost against tracing the frame. Each target is met twice, with the keys' moved
// scene points predicting the pixels near edges the inner keys disagree on (PathMethod::MovedEdge)
// and without (those pixels all re-traced): the before and after of that method, in one run.
// Prints a Markdown section for bench/REPORT.md.
// Usage: asrt_bench_path   (from the repository root)
// Environment, to keep a run short or widen it: ASRT_BENCH_PATH_SIDE (frame side, 200),
// ASRT_BENCH_PATH_FRAMES (0: the four frames midway between h = 0.055 keys; N: the N frames of a
// movie along the ramp, those that are not keys), ASRT_BENCH_PATH_SPACINGS (key spacings,
// "0.11,0.055"), ASRT_BENCH_PATH_TARGETS (dB, "30,35,40"), ASRT_BENCH_PATH_REFERENCE (samples a
// side of the converged frames, 8: point samples in the study, filtered ones in the paths table),
// ASRT_BENCH_PATH_STUDY (0 leaves out the mass ramp's study above), ASRT_BENCH_PATH_DUMP (a
// directory: each study frame's pixels, their way of predicting, estimate, true error, surfaces
// and the keys' leave-one-out error, as CSV, and the preview, plain, traced and converged pictures
// as raw RGB; and each path frame's pixels, their way, estimate, true error and surfaces).
// Then, at one key spacing each, the paths of ASRT_BENCH_PATH_PATHS ("ramp,orbit,kerr-orbit,spin",
// "none" for none; NAME:H sets a path's key spacing): the mass ramp, a 90° camera orbit of Fig. 1,
// the Kerr disk orbited through 90°, and its spin ramped a = 0 → 0.99; on
// ASRT_BENCH_PATH_PATH_FRAMES frames (4) midway between keys, spread along the path: the plain
// preview and --quality at each of ASRT_BENCH_PATH_PATH_TARGETS ("30,35,40"), held to converged
// pictures (the inner keys' own error measured by probes, SettingsError.h) and scored against
// them, and the estimate's rank correlation. ASRT_BENCH_PATH_KEY_PRESET = NAME traces the keys,
// and the frames at s that re-trace, with that preset's rendering (renderingPreset; unset: the
// scene's own): settings that can reach a higher target.
#include "ErrorEstimate.h"
#include "FrameMatching.h"
#include "FrameTracer.h"
#include "GeodesicMovie.h"
#include "GeodesicSceneLoading.h"
#include "ImageQuality.h"
#include "KdTreeIndex.h"
#include "LeaveOneOut.h"
#include "PathInterpolation.h"
#include "SettingsError.h"
#include "Spacetime.h"

#include <omp.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <map>
#include <numeric>
#include <sstream>
#include <string>
#include <vector>

using namespace asrt;

namespace
{
const std::string kScene = "Data/scenes/fig4-mass-start.json";
int kSide = 200;
int kReferenceSide = 8;
/// The keys' (and the frames traced at s') rendering preset in the paths table
/// (renderingPreset); empty: the scene's own rendering.
std::string kKeyPreset;

/// The rendering the paths table traces keys and frames at s with (null: the scene's).
const AntialiasOptions* keyRendering()
{
  static AntialiasOptions o;
  if (kKeyPreset.empty())
    return nullptr;
  o = renderingPreset(kKeyPreset);
  return &o;
}

double envNumber(const char* name, double fallback)
{
  const char* v = std::getenv(name);
  return v && *v ? std::atof(v) : fallback;
}

std::vector<double> envList(const char* name, const std::vector<double>& fallback)
{
  const char* v = std::getenv(name);
  if (!v || !*v)
    return fallback;
  std::vector<double> out;
  std::stringstream in(v);
  std::string item;
  while (std::getline(in, item, ','))
    out.push_back(std::atof(item.c_str()));
  return out;
}

double now()
{
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

SceneDescription rampScene(double mass, const AntialiasOptions* rendering = nullptr)
{
  SceneDescription d = loadSceneFile(kScene, vtkImageFileLoader());
  d.camera.width = d.camera.height = kSide;
  d.spacetime.mass = mass;
  if (rendering)
    d.rendering = *rendering;
  return d;
}

/// The ramp's spacetime at mass s (PathOptions::spacetimeAt).
SpacetimeAlongPath rampSpacetime()
{
  return [hole = rampScene(0.5).spacetime](double s) -> std::shared_ptr<const Spacetime>
  {
    SpacetimeParameters at = hole;
    at.mass = s;
    return makeSpacetime(at);
  };
}

std::vector<std::uint8_t> rgbOf(const std::vector<RayRecord>& records)
{
  std::vector<std::uint8_t> rgb(3 * records.size());
  for (std::size_t p = 0; p < records.size(); ++p)
  {
    const auto c = imageColor(records[p].color);
    std::copy(c.begin(), c.end(), &rgb[3 * p]);
  }
  return rgb;
}

double psnrOf(const std::vector<std::uint8_t>& a, const std::vector<std::uint8_t>& b)
{
  return psnr(RgbView{ kSide, kSide, a.data() }, RgbView{ kSide, kSide, b.data() });
}

double error2(const std::vector<std::uint8_t>& a, const std::vector<std::uint8_t>& b, std::size_t p)
{
  double s = 0;
  for (int c = 0; c < 3; ++c)
  {
    const double d = double(a[3 * p + c]) - double(b[3 * p + c]);
    s += d * d;
  }
  return s;
}

/// The smallest share of pixels that, re-traced in the given order after the must-re-trace ones,
/// brings the frame to `db` against the traced frame.
double shareFor(const std::vector<std::size_t>& order, std::size_t must,
                const std::vector<double>& err2, double db)
{
  const double n = static_cast<double>(err2.size());
  double left = 0;
  for (std::size_t k = must; k < order.size(); ++k)
    left += err2[order[k]];
  for (std::size_t k = must; k <= order.size(); ++k)
  {
    if (psnrOfMse(left / (3.0 * n)) >= db)
      return k / n;
    if (k < order.size())
      left -= err2[order[k]];
  }
  return 1.0;
}

std::string pct(double x)
{
  char s[32];
  std::snprintf(s, sizeof s, "%.1f %%", 100 * x);
  return s;
}

std::string dbs(double x)
{
  char s[32];
  if (std::isinf(x))
    return "∞";
  std::snprintf(s, sizeof s, "%.1f", x);
  return s;
}

/// A movie path for the paths table: the scene and how the parameter s sets it.
struct BenchPath
{
  std::string name, scene, parameter;
  double from = 0, to = 1, h = 0.1;
  std::function<void(SceneDescription&, double)> apply;
};

std::vector<BenchPath> benchPaths()
{
  auto mass = [](SceneDescription& d, double s) { d.spacetime.mass = s; };
  auto spin = [](SceneDescription& d, double s) { d.spacetime.spin = s; };
  // The scene's camera turned about the hole's axis, as `asrt movie --orbit` turns it.
  auto orbit = [](SceneDescription& d, double degrees)
  {
    const CameraPose pose =
      turnedAboutZ({ d.camera.position, d.camera.focalPoint, d.camera.viewUp }, degrees);
    d.camera.position = pose.position;
    d.camera.focalPoint = pose.focalPoint;
    d.camera.viewUp = pose.viewUp;
  };
  return { { "ramp", kScene, "M", 0.1, 1.2, 0.055, mass },
           { "orbit", "Data/scenes/fig1-cylinders.json", "degrees", 0, 90, 2, orbit },
           { "kerr-orbit", "Data/scenes/kerr-disk.json", "degrees", 0, 90, 10, orbit },
           { "spin", "Data/scenes/kerr-disk.json", "a", 0, 0.99, 0.198, spin } };
}

/// The path's scene at s, `kSide` a side, with `rendering` if given.
SceneDescription pathScene(const BenchPath& path, double s,
                           const AntialiasOptions* rendering = nullptr)
{
  SceneDescription d = loadSceneFile(path.scene, vtkImageFileLoader());
  d.camera.width = d.camera.height = kSide;
  path.apply(d, s);
  if (rendering)
    d.rendering = *rendering;
  return d;
}

/// The path's spacetime at s (PathOptions::spacetimeAt).
std::function<std::shared_ptr<const Spacetime>(double)> spacetimeAlong(const BenchPath& path)
{
  const SceneDescription d = pathScene(path, path.from);
  return [path, d](double s) -> std::shared_ptr<const Spacetime>
  {
    SceneDescription at = d;
    path.apply(at, s);
    return makeSpacetime(at.spacetime);
  };
}

/// One path frame's scores; the completions' per target (the paths table's targets).
struct PathScore
{
  double s = 0, tracedVsConverged = 0, mustBefore = 0, plainVsConverged = 0, plainVsTraced = 0,
         spearman = 0, spearmanUnrounded = 0, settingsBound = 0;
  std::vector<double> share, doneVsConverged, doneVsTraced, estimated;
  /// Per target: the share traced with the converged rendering (SettingsRefinement), and the
  /// rays the completion integrated over those the frame traced at s took.
  std::vector<double> convergedShare, raysOverTraced;
};

/// The settings' own error of a key at s (SettingsError.h): its probes traced converged.
SettingsError keySettingsError(const BenchPath& path, double s, const std::vector<RayRecord>& key)
{
  const AntialiasOptions converged = convergedRendering();
  const FrameTracer tracer(pathScene(path, s, &converged));
  return measureSettingsError(key, kSide, kSide, pixelTracerOf(tracer));
}

/// The frame at s from the keys around it (traced once each, into `keys`, their settings' errors
/// into `settings`), scored plain and completed to each target against the converged picture.
PathScore scorePathFrame(const BenchPath& path, int interval, int intervals,
                         const std::vector<double>& targets,
                         std::map<int, std::vector<RayRecord>>& keys,
                         std::map<int, SettingsError>& settings, const Scene& shading)
{
  PathScore r;
  r.s = path.from + (interval + 0.5) * path.h;
  std::vector<PathKey> around;
  // The nearest 4 keys: 2 on either side, or at an end of the path the 4 there.
  const int firstKey = std::clamp(interval - 1, 0, std::max(0, intervals - 3));
  for (int k = firstKey; k <= std::min(intervals, firstKey + 3); ++k)
  {
    if (!keys.count(k))
      keys[k] =
        FrameTracer(pathScene(path, path.from + k * path.h, keyRendering())).traceRows(0, kSide);
    around.push_back({ path.from + k * path.h, &keys[k] });
  }
  for (int k : { interval, interval + 1 })
    if (!settings.count(k))
      settings[k] = keySettingsError(path, path.from + k * path.h, keys[k]);
  const SettingsError held = pooled(settings[interval], settings[interval + 1]);
  r.settingsBound = held.psnr();
  const SceneDescription atS = pathScene(path, r.s, keyRendering());
  const FrameTracer tracer(atS);
  const std::vector<RayRecord> tracedRecords = tracer.traceRows(0, kSide);
  const std::vector<std::uint8_t> traced = rgbOf(tracedRecords);
  const double tracedRays = static_cast<double>(tracer.raysIntegrated());
  const AntialiasOptions converged = convergedRendering(kReferenceSide);
  const std::vector<std::uint8_t> reference =
    rgbOf(FrameTracer(pathScene(path, r.s, &converged)).traceRows(0, kSide));
  r.tracedVsConverged = psnrOf(traced, reference);
  // The completion re-traces scattered pixels each with its own centre ray, as the path
  // interpolator and the movie do: the keys' grid would trace each one's whole lattice block.
  SceneDescription scattered = atS;
  scattered.rendering = scatteredPixelRendering(scattered.rendering);
  const FrameTracer retracer(scattered);
  PathOptions with, without;
  with.pointIndex = kdTreeIndexFactory();
  with.spacetimeAt = spacetimeAlong(path);
  without.movedEdges = false;
  const double n = double(kSide) * kSide;
  r.mustBefore = interpolateAlongPath(around, r.s, kSide, kSide, shading, without)
                   .counts()[static_cast<std::size_t>(PathMethod::Retrace)] /
                 n;
  const PathFrame plain = interpolateAlongPath(around, r.s, kSide, kSide, shading, with);
  const std::vector<std::uint8_t> plainRgb = rgbOf(plain.records);
  // The plain preview: the frame shown as predicted, the shadow's rim hedged.
  PathOptions preview = with;
  preview.hedgeNearShadow = true;
  const std::vector<std::uint8_t> previewRgb =
    rgbOf(interpolateAlongPath(around, r.s, kSide, kSide, shading, preview).records);
  r.plainVsConverged = psnrOf(previewRgb, reference);
  r.plainVsTraced = psnrOf(previewRgb, traced);
  std::vector<double> est, truth, truthUnrounded;
  for (std::size_t p = 0; p < plain.records.size(); ++p)
    if (plain.method[p] != static_cast<std::uint8_t>(PathMethod::Retrace))
    {
      est.push_back(plain.estimate[p]);
      truth.push_back(error2(plainRgb, traced, p));
      truthUnrounded.push_back(colorError2(plain.records[p].color, tracedRecords[p].color));
    }
  r.spearman = spearman(est, truth);
  r.spearmanUnrounded = spearman(est, truthUnrounded);
  if (const char* dump = std::getenv("ASRT_BENCH_PATH_DUMP"))
  {
    char name[512];
    std::snprintf(name, sizeof name, "%s/%s-%.4f.csv", dump, path.name.c_str(), r.s);
    if (FILE* out = std::fopen(name, "w"))
    {
      std::fprintf(out, "p,method,estimate,errf,obj,objt,term,termt\n");
      for (std::size_t p = 0; p < plain.records.size(); ++p)
        std::fprintf(out, "%zu,%d,%.9g,%.9g,%d,%d,%d,%d\n", p, int(plain.method[p]),
                     double(plain.estimate[p]),
                     double(colorError2(plain.records[p].color, tracedRecords[p].color)),
                     plain.records[p].objectId, tracedRecords[p].objectId,
                     int(plain.records[p].termination), int(tracedRecords[p].termination));
      std::fclose(out);
    }
  }
  for (double target : targets)
  {
    PathFrame done = plain;
    // As vtkGeodesicPathInterpolator does by default (RaiseRenderingForTarget): where the keys'
    // settings fall short of the target, the strata holding their error traced converged.
    const AntialiasOptions judge = convergedRendering(convergedSideFor(target));
    const FrameTracer convergedAtS(pathScene(path, r.s, &judge));
    const PathCompletion c = completePathFrame(done, pixelTracerOf(retracer), target, 0.01,
                                               refinementFor(held, convergedAtS));
    r.convergedShare.push_back(c.refined / n);
    r.raysOverTraced.push_back(c.raysTraced / tracedRays);
    const std::vector<std::uint8_t> doneRgb = rgbOf(done.records);
    r.share.push_back(c.retraced / n);
    r.doneVsConverged.push_back(psnrOf(doneRgb, reference));
    r.doneVsTraced.push_back(psnrOf(doneRgb, traced));
    r.estimated.push_back(c.estimatedPsnr);
  }
  return r;
}

/// The paths table: per path, at its one key spacing, and per target, the mean (and worst) over
/// its frames.
void printPaths(const std::vector<BenchPath>& paths, int frameCount,
                const std::vector<double>& targets)
{
  std::printf("\n**Four paths** at one key spacing each (h: the must-re-trace share without moved "
              "edges lands near 10–20 %%), %d frames each midway between keys, spread along the "
              "path; 4 keys around each (`interpolateAlongPath` with moved edges, matched over "
              "`kdTreeIndexFactory()`); converged: %d×%d filtered samples a pixel, every centre "
              "ray traced (`convergedRendering`); keys and frames traced at s with %s. "
              "**Plain**: nothing re-traced. **--quality T**: "
              "`completePathFrame` held to the converged picture: the inner keys' own error "
              "against theirs measured by probes traced converged (`measureSettingsError`, the "
              "the inner keys' probes pooled, its bound in column *settings*); where that bound "
              "falls short of T, the strata holding the keys' error traced with the rendering "
              "that judges T (`SettingsRefinement`, `convergedSideFor`: 8×8 above 36 dB), as "
              "`vtkGeodesicPathInterpolator` does by default: *converged*, the share of pixels "
              "traced so; *rays × traced*, the rays the completion integrated (its pixels each "
              "traced with its own centre ray, `scatteredPixelRendering`, as the interpolator "
              "and the movie trace them) over those of the frame traced at s (mean). PSNR as "
              "mean / "
              "worst; Spearman of the "
              "estimate against the true error (against the traced frame) over the predicted "
              "pixels, mean / worst, against the error of the 8-bit colours (most pixels tie at "
              "0) and against the error of the colours before rounding; *below T − 1*: frames "
              "under T − 1 dB against converged:\n\n",
              frameCount, kReferenceSide, kReferenceSide,
              kKeyPreset.empty() ? "the scene's rendering"
                                 : ("the `" + kKeyPreset + "` preset's rendering").c_str());
  std::printf(
    "| path | scene | h | traced vs converged | must re-trace without moved edges | "
    "plain vs converged | plain vs traced | Spearman | Spearman (unrounded) | T | settings | "
    "re-traced | converged | rays × traced | vs converged | below T − 1 | estimated | "
    "vs traced | time |\n"
    "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (const BenchPath& path : paths)
  {
    const double t0 = now();
    const int intervals = static_cast<int>(std::lround((path.to - path.from) / path.h));
    if (intervals < 1 || std::abs(intervals * path.h - (path.to - path.from)) > 1e-9 * path.to)
    {
      std::fprintf(stderr, "%s: the key spacing %g does not divide the path\n", path.name.c_str(),
                   path.h);
      std::exit(2);
    }
    const SceneDescription shading = pathScene(path, path.from);
    std::map<int, std::vector<RayRecord>> keys;
    std::map<int, SettingsError> settings;
    std::vector<PathScore> scores;
    for (int f = 0; f < frameCount; ++f)
    {
      const int interval = std::max(0, (f + 1) * intervals / frameCount - 1);
      scores.push_back(
        scorePathFrame(path, interval, intervals, targets, keys, settings, *shading.scene));
      const PathScore& r = scores.back();
      std::fprintf(stderr, "%s, %s = %.4g: traced %.1f dB, settings %.1f, plain %.1f dB, rho %.2f",
                   path.name.c_str(), path.parameter.c_str(), r.s, r.tracedVsConverged,
                   r.settingsBound, r.plainVsConverged, r.spearman);
      for (std::size_t t = 0; t < targets.size(); ++t)
        std::fprintf(stderr, "; q%.0f %.1f %% (%.1f %% converged, %.2f x rays) %.1f dB (est. %.1f)",
                     targets[t], 100 * r.share[t], 100 * r.convergedShare[t], r.raysOverTraced[t],
                     r.doneVsConverged[t], r.estimated[t]);
      std::fprintf(stderr, " (%.0f s)\n", now() - t0);
    }
    const double elapsed = now() - t0;
    auto meanWorst = [&](const std::function<double(const PathScore&)>& field, bool percent)
    {
      double sum = 0, worst = 1e300;
      for (const PathScore& r : scores)
      {
        sum += std::min(field(r), 99.0);
        worst = std::min(worst, field(r));
      }
      const double mean = sum / static_cast<double>(scores.size());
      return percent ? pct(mean) : dbs(mean) + " / " + dbs(worst);
    };
    double rhoSum[2] = { 0, 0 }, rhoWorst[2] = { 1, 1 };
    for (const PathScore& r : scores)
      for (int u = 0; u < 2; ++u)
      {
        const double rho = u ? r.spearmanUnrounded : r.spearman;
        rhoSum[u] += rho;
        rhoWorst[u] = std::min(rhoWorst[u], rho);
      }
    char spearmanText[2][64];
    for (int u = 0; u < 2; ++u)
      std::snprintf(spearmanText[u], sizeof spearmanText[u], "%.2f / %.2f",
                    rhoSum[u] / static_cast<double>(scores.size()), rhoWorst[u]);
    char spacing[64];
    std::snprintf(spacing, sizeof spacing, "%g %s", path.h, path.parameter.c_str());
    for (std::size_t t = 0; t < targets.size(); ++t)
    {
      int below = 0;
      for (const PathScore& r : scores)
        below += r.doneVsConverged[t] < targets[t] - 1.0;
      const bool first = t == 0;
      std::printf(
        "| %s | %s | %s | %s | %s | %s | %s | %s | %s | %.0f | %s | %s | %s | %.2f | %s | %d of "
        "%zu | %s | %s | %s |\n",
        first ? path.name.c_str() : "", first ? ("`" + path.scene + "`").c_str() : "",
        first ? spacing : "",
        first ? meanWorst([](const PathScore& r) { return r.tracedVsConverged; }, false).c_str()
              : "",
        first ? meanWorst([](const PathScore& r) { return r.mustBefore; }, true).c_str() : "",
        first ? meanWorst([](const PathScore& r) { return r.plainVsConverged; }, false).c_str()
              : "",
        first ? meanWorst([](const PathScore& r) { return r.plainVsTraced; }, false).c_str() : "",
        first ? spearmanText[0] : "", first ? spearmanText[1] : "", targets[t],
        meanWorst([](const PathScore& r) { return r.settingsBound; }, false).c_str(),
        meanWorst([t](const PathScore& r) { return r.share[t]; }, true).c_str(),
        meanWorst([t](const PathScore& r) { return r.convergedShare[t]; }, true).c_str(),
        [&]
        {
          double sum = 0;
          for (const PathScore& r : scores)
            sum += r.raysOverTraced[t];
          return sum / static_cast<double>(scores.size());
        }(),
        meanWorst([t](const PathScore& r) { return r.doneVsConverged[t]; }, false).c_str(), below,
        scores.size(), meanWorst([t](const PathScore& r) { return r.estimated[t]; }, false).c_str(),
        meanWorst([t](const PathScore& r) { return r.doneVsTraced[t]; }, false).c_str(),
        first ? (std::to_string(static_cast<int>(elapsed)) + " s").c_str() : "");
    }
  }
}

/// The paths ASRT_BENCH_PATH_PATHS names (NAME or NAME:H), all four by default.
std::vector<BenchPath> selectedPaths()
{
  const std::vector<BenchPath> all = benchPaths();
  const char* v = std::getenv("ASRT_BENCH_PATH_PATHS");
  if (!v || !*v)
    return all;
  std::vector<BenchPath> out;
  std::stringstream in(v);
  std::string item;
  while (std::getline(in, item, ','))
  {
    const std::size_t colon = item.find(':');
    const std::string name = item.substr(0, colon);
    bool known = name == "none";
    for (const BenchPath& p : all)
      if (p.name == name)
      {
        known = true;
        out.push_back(p);
        if (colon != std::string::npos)
          out.back().h = std::atof(item.c_str() + colon + 1);
      }
    if (!known)
    {
      std::fprintf(stderr, "ASRT_BENCH_PATH_PATHS: unknown path \"%s\"\n", name.c_str());
      std::exit(2);
    }
  }
  return out;
}

struct Frame
{
  double mass = 0;
  std::vector<RayRecord> traced; ///< same settings as the keys
  double traceSeconds = 0;
  double rays = 0; ///< every ray integrated to trace it (FrameTracer::raysIntegrated)
  std::vector<std::uint8_t> tracedRgb, reference;
};
}

namespace
{
/// The mass ramp's study: key spacings, targets, moved edges against all re-traced.
void runRampStudy(double tStart)
{
  const int movieFrames = static_cast<int>(envNumber("ASRT_BENCH_PATH_FRAMES", 0));
  const std::vector<double> spacings = envList("ASRT_BENCH_PATH_SPACINGS", { 0.11, 0.055 });
  const std::vector<double> targets = envList("ASRT_BENCH_PATH_TARGETS", { 30, 35, 40 });
  // Frames between keys on both spacings' lattices (0.1 + k h): midway between the h = 0.055 keys;
  // or a movie's frames along the ramp, less those on a key (interpolation returns keys as such).
  std::vector<double> masses = { 0.3475, 0.6225, 0.8975, 1.1725 };
  if (movieFrames >= 2)
  {
    masses.clear();
    for (int k = 0; k < movieFrames; ++k)
    {
      const double m = 0.1 + 1.1 * k / (movieFrames - 1);
      bool onKey = false;
      for (double h : spacings)
        onKey = onKey || std::abs((m - 0.1) / h - std::round((m - 0.1) / h)) < 1e-9;
      if (!onKey)
        masses.push_back(m);
    }
  }
  const bool detailed = masses.size() <= 8;
  std::vector<Frame> frames;
  AntialiasOptions referenceRendering;
  referenceRendering.mode = AntialiasMode::None;
  referenceRendering.supersample = kReferenceSide;
  double referenceSeconds = 0;
  for (double m : masses)
  {
    Frame f;
    f.mass = m;
    const SceneDescription d = rampScene(m);
    const double t0 = now();
    const FrameTracer tracer(d);
    f.traced = tracer.traceRows(0, kSide);
    f.traceSeconds = now() - t0;
    f.rays = static_cast<double>(tracer.raysIntegrated());
    f.tracedRgb = rgbOf(f.traced);
    const double t1 = now();
    f.reference = rgbOf(FrameTracer(rampScene(m, &referenceRendering)).traceRows(0, kSide));
    referenceSeconds += now() - t1;
    std::fprintf(stderr, "frame M = %.4f traced (%.2f s) with its reference\n", m, f.traceSeconds);
    frames.push_back(std::move(f));
  }
  double traceSeconds = 0;
  for (const Frame& f : frames)
    traceSeconds += f.traceSeconds;
  traceSeconds /= static_cast<double>(frames.size());

  std::string frameText;
  if (movieFrames >= 2)
    frameText = "the " + std::to_string(masses.size()) + " frames of a " +
                std::to_string(movieFrames) + "-frame movie along it that are not keys";
  else
    frameText = "frames at M = 0.3475, 0.6225, 0.8975, 1.1725 (midway between h = 0.055 keys)";
  std::printf(
    "- **Set-up.** `%s` at %d×%d, the default rendering, its mass ramp M = 0.1 → 1.2 "
    "with key frames every h; %s. **Converged**: %d×%d point samples a pixel (%.0f s for all). "
    "**Traced**: the frame traced at its mass with the keys' settings (%.2f s a frame "
    "on average). Each interpolated frame comes from the 4 keys around it "
    "(`interpolateAlongPath`), then `completePathFrame` re-traces to the target (against "
    "the traced frame; each re-traced pixel its own centre ray, `scatteredPixelRendering`, as "
    "the path interpolator traces them); its re-traced share counts every ray traced at t (the "
    "must-re-trace pixels, the chosen ones and the probes). **Moved edges**: the pixels near an "
    "edge the inner keys disagree on predicted from the keys' scene points moved through the "
    "chain (`PathOptions::movedEdges`, the default); **all re-traced**: without, every such pixel "
    "re-traced (the method before moved edges).\n\n",
    kScene.c_str(), kSide, kSide, frameText.c_str(), kReferenceSide, kReferenceSide,
    referenceSeconds, traceSeconds);

  if (detailed)
    std::printf("| h | M | traced vs converged | method | re-traced | vs traced | vs converged | "
                "time (× trace) |\n|---|---|---|---|---|---|---|---|\n");
  struct Ranking
  {
    double h, mass, spearman, spearmanUnrounded, ceiling, mustBefore, must, moved, estimate35,
      oracle35, estimate40, oracle40;
  };
  struct Outcome
  {
    double h, target;
    bool moved;
    double share, vsTraced, vsConverged;
  };
  struct PlainError
  {
    double h, mass, psnr, previewPsnr;
    std::array<double, kPathMethodCount> pixels{}, error{}; ///< shares of all
    double movedOtherSurface = 0, movedOtherError = 0;      ///< shares of the moved edges'
    /// Spearman of the estimate against the error before rounding within each way (NaN: fewer
    /// than 16 pixels).
    std::array<double, kPathMethodCount> rank{};
  };
  std::vector<Ranking> rankings;
  std::vector<Outcome> outcomes;
  std::vector<PlainError> plainErrors;
  for (double h : spacings)
  {
    const int K = static_cast<int>(std::lround(1.1 / h)) + 1;
    std::vector<double> s(K);
    std::vector<std::vector<RayRecord>> keys(K);
    for (int k = 0; k < K; ++k)
    {
      s[k] = 0.1 + k * h;
      keys[k] = FrameTracer(rampScene(s[k])).traceRows(0, kSide);
    }
    std::fprintf(stderr, "h = %g: %d key frames traced\n", h, K);
    const SceneDescription shading = rampScene(0.5);
    for (const Frame& f : frames)
    {
      std::vector<PathKey> path;
      for (int k = 0; k < K; ++k)
        path.push_back({ s[k], &keys[k] });
      const double tracedVsRef = psnrOf(f.tracedRgb, f.reference);
      PathOptions with, without;
      with.pointIndex = kdTreeIndexFactory();
      with.spacetimeAt = rampSpacetime();
      without.movedEdges = false;
      const double tPlain = now();
      const PathFrame plain =
        interpolateAlongPath(path, f.mass, kSide, kSide, *shading.scene, with);
      const double plainSeconds = now() - tPlain;
      const PathFrame plainBefore =
        interpolateAlongPath(path, f.mass, kSide, kSide, *shading.scene, without);
      // The plain preview: the frame shown as predicted, the shadow's rim hedged; the frames
      // completed to a target start from `plain`.
      PathOptions preview = with;
      preview.hedgeNearShadow = true;
      const std::vector<std::uint8_t> previewRgb =
        rgbOf(interpolateAlongPath(path, f.mass, kSide, kSide, *shading.scene, preview).records);
      // The plain frame, the estimate's ranking against the truth, and the oracle.
      const std::vector<std::uint8_t> plainRgb = rgbOf(plain.records);
      std::vector<double> err2(plain.records.size()), est, truth, truthUnrounded;
      std::size_t must = 0;
      for (std::size_t p = 0; p < err2.size(); ++p)
      {
        err2[p] = error2(plainRgb, f.tracedRgb, p);
        if (plain.method[p] == static_cast<std::uint8_t>(PathMethod::Retrace))
        {
          ++must;
          continue;
        }
        est.push_back(plain.estimate[p]);
        truth.push_back(err2[p]);
        truthUnrounded.push_back(colorError2(plain.records[p].color, f.traced[p].color));
      }
      {
        // Where the plain frame's error lies: each way of predicting, its share of the pixels and
        // of the squared error against the traced frame; for moved edges also the pixels whose
        // centre shows another surface than the traced frame's.
        PlainError e{ h, f.mass, psnrOf(plainRgb, f.tracedRgb), psnrOf(previewRgb, f.tracedRgb) };
        double total = 0, movedError = 0, otherSurface = 0, otherError = 0;
        const auto moved = static_cast<std::uint8_t>(PathMethod::MovedEdge);
        for (std::size_t p = 0; p < err2.size(); ++p)
        {
          e.pixels[plain.method[p]] += 1.0 / static_cast<double>(err2.size());
          e.error[plain.method[p]] += err2[p];
          total += err2[p];
          if (plain.method[p] != moved)
            continue;
          movedError += err2[p];
          const RayRecord &a = plain.records[p], &b = f.traced[p];
          if (a.objectId != b.objectId || a.termination != b.termination)
          {
            otherSurface += 1;
            otherError += err2[p];
          }
        }
        for (double& x : e.error)
          x = total > 0 ? x / total : 0.0;
        for (int m = 0; m < kPathMethodCount; ++m)
        {
          std::vector<double> wayEstimate, wayError;
          for (std::size_t p = 0; p < err2.size(); ++p)
            if (plain.method[p] == m)
            {
              wayEstimate.push_back(plain.estimate[p]);
              wayError.push_back(colorError2(plain.records[p].color, f.traced[p].color));
            }
          e.rank[static_cast<std::size_t>(m)] =
            wayEstimate.size() >= 16 ? spearman(wayEstimate, wayError) : std::nan("");
        }
        const double movedPixels = e.pixels[moved] * static_cast<double>(err2.size());
        e.movedOtherSurface = movedPixels > 0 ? otherSurface / movedPixels : 0.0;
        e.movedOtherError = movedError > 0 ? otherError / movedError : 0.0;
        plainErrors.push_back(e);
      }
      if (const char* dump = std::getenv("ASRT_BENCH_PATH_DUMP"))
      {
        char name[512];
        std::snprintf(name, sizeof name, "%s/h%g-M%.4f.csv", dump, h, f.mass);
        if (FILE* out = std::fopen(name, "w"))
        {
          // The keys' leave-one-out error at each pixel, not dilated.
          const std::vector<float> loo =
            leaveOneOutError(path, f.mass, kSide, kSide, *shading.scene, with, 0);
          std::fprintf(out, "p,method,estimate,err8,errf,obj,objt,term,termt,loo\n");
          for (std::size_t p = 0; p < err2.size(); ++p)
            std::fprintf(out, "%zu,%d,%.9g,%.9g,%.9g,%d,%d,%d,%d,%.9g\n", p, int(plain.method[p]),
                         double(plain.estimate[p]), err2[p],
                         double(colorError2(plain.records[p].color, f.traced[p].color)),
                         plain.records[p].objectId, f.traced[p].objectId,
                         int(plain.records[p].termination), int(f.traced[p].termination),
                         loo.empty() ? 0.0 : double(loo[p]));
          std::fclose(out);
        }
        // The pictures, raw 8-bit RGB rows from the bottom: the preview, the plain frame, the
        // frame traced at t, its converged reference, and the inner pair of keys as traced.
        const std::size_t inner =
          static_cast<std::size_t>(std::upper_bound(s.begin(), s.end(), f.mass) - s.begin());
        const std::vector<std::uint8_t> key0 = rgbOf(keys[inner - 1]), key1 = rgbOf(keys[inner]);
        const std::pair<const char*, const std::vector<std::uint8_t>*> pictures[] = {
          { "preview", &previewRgb },    { "plain", &plainRgb }, { "traced", &f.tracedRgb },
          { "converged", &f.reference }, { "key0", &key0 },      { "key1", &key1 }
        };
        for (const auto& [what, rgb] : pictures)
        {
          std::snprintf(name, sizeof name, "%s/h%g-M%.4f-%s.rgb", dump, h, f.mass, what);
          if (FILE* out = std::fopen(name, "wb"))
          {
            std::fwrite(rgb->data(), 1, rgb->size(), out);
            std::fclose(out);
          }
        }
      }
      const std::vector<std::int32_t> byEstimate32 = retraceOrder(plain.estimate);
      std::vector<std::size_t> byEstimate(byEstimate32.begin(), byEstimate32.end());
      std::vector<std::size_t> byTruth = byEstimate;
      std::stable_sort(byTruth.begin() + must, byTruth.end(),
                       [&](std::size_t a, std::size_t b) { return err2[a] > err2[b]; });
      const double n = static_cast<double>(err2.size());
      rankings.push_back(
        { h, f.mass, spearman(est, truth), spearman(est, truthUnrounded),
          spearman(truthUnrounded, truth),
          plainBefore.counts()[static_cast<std::size_t>(PathMethod::Retrace)] / n, must / n,
          (plain.counts()[static_cast<std::size_t>(PathMethod::MovedEdge)] +
           plain.counts()[static_cast<std::size_t>(PathMethod::MovedSurface)]) /
            n,
          shareFor(byEstimate, must, err2, 35), shareFor(byTruth, must, err2, 35),
          shareFor(byEstimate, must, err2, 40), shareFor(byTruth, must, err2, 40) });
      if (detailed)
        std::printf("| %g | %.4f | %s | plain (nothing re-traced) | 0 | %s | %s | %.2f |\n", h,
                    f.mass, dbs(tracedVsRef).c_str(), dbs(psnrOf(previewRgb, f.tracedRgb)).c_str(),
                    dbs(psnrOf(previewRgb, f.reference)).c_str(), plainSeconds / f.traceSeconds);
      // Scattered pixels each with its own centre ray, as the path interpolator re-traces them.
      SceneDescription atT = rampScene(f.mass);
      atT.rendering = scatteredPixelRendering(atT.rendering);
      const FrameTracer tracer(atT);
      for (double target : targets)
        for (const bool moved : { false, true })
        {
          PathFrame done = moved ? plain : plainBefore;
          const double t0 = now();
          const PathCompletion c = completePathFrame(done, tracer, target);
          const double seconds = now() - t0;
          const std::vector<std::uint8_t> rgb = rgbOf(done.records);
          const Outcome o{ h,
                           target,
                           moved,
                           double(c.retraced) / done.records.size(),
                           psnrOf(rgb, f.tracedRgb),
                           psnrOf(rgb, f.reference) };
          outcomes.push_back(o);
          if (detailed)
            std::printf("| %g | %.4f | | --quality %.0f, %s | %s | %s | %s | %.2f |\n", h, f.mass,
                        target, moved ? "moved edges" : "all re-traced", pct(o.share).c_str(),
                        dbs(o.vsTraced).c_str(), dbs(o.vsConverged).c_str(),
                        seconds / f.traceSeconds);
        }
      std::fprintf(stderr, "h = %g, M = %.4f done (%.0f s so far)\n", h, f.mass, now() - tStart);
    }
  }
  std::printf("\n**Moved edges against all re-traced**, per key spacing and target, over the %zu "
              "frames: the share re-traced (mean), PSNR against the converged and the traced frame "
              "(mean / worst), and the frames below the target less 1 dB against each:\n\n",
              frames.size());
  std::printf("| h | target | near edges | re-traced | vs converged | vs traced | below T − 1 "
              "(converged) | below T − 1 (traced) |\n|---|---|---|---|---|---|---|---|\n");
  for (double h : spacings)
    for (double target : targets)
      for (const bool moved : { false, true })
      {
        double share = 0, conv = 0, trac = 0, worstConv = 1e9, worstTrac = 1e9, count = 0;
        int belowConv = 0, belowTrac = 0;
        for (const Outcome& o : outcomes)
          if (o.h == h && o.target == target && o.moved == moved)
          {
            count += 1;
            share += o.share;
            conv += std::min(o.vsConverged, 99.0);
            trac += std::min(o.vsTraced, 99.0);
            worstConv = std::min(worstConv, o.vsConverged);
            worstTrac = std::min(worstTrac, o.vsTraced);
            belowConv += o.vsConverged < target - 1;
            belowTrac += o.vsTraced < target - 1;
          }
        std::printf("| %g | %.0f | %s | %s | %s / %s | %s / %s | %d | %d |\n", h, target,
                    moved ? "moved edges" : "all re-traced", pct(share / count).c_str(),
                    dbs(conv / count).c_str(), dbs(worstConv).c_str(), dbs(trac / count).c_str(),
                    dbs(worstTrac).c_str(), belowConv, belowTrac);
      }
  std::printf(
    "\n**The estimate against the truth** (the plain frame's pixels that the keys vouch "
    "for, moved edges included; Spearman against the error of the frame's 8-bit colours, where "
    "most pixels tie at 0, and against the error of its colours before rounding; *ceiling*: "
    "the error before rounding itself against the 8-bit error, what an estimate that knew the "
    "true error exactly would score against the rounded one; "
    "the share re-traced in all, the must-re-trace pixels first, for "
    "the frame to reach 35 or 40 dB against the traced frame when pixels are re-traced in the "
    "estimate's order and in the true error's, the oracle; must re-trace before: without moved "
    "edges):\n\n");
  std::printf("| h | M | Spearman | Spearman (unrounded) | ceiling | must re-trace before | moved "
              "edges | must re-trace | 35 dB: estimate | 35 dB: oracle | 40 dB: estimate | 40 dB: "
              "oracle |\n|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (double h : spacings)
  {
    Ranking mean{ h, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0 };
    double count = 0;
    for (const Ranking& r : rankings)
    {
      if (r.h != h)
        continue;
      if (detailed)
        std::printf("| %g | %.4f | %.2f | %.2f | %.2f | %s | %s | %s | %s | %s | %s | %s |\n", r.h,
                    r.mass, r.spearman, r.spearmanUnrounded, r.ceiling, pct(r.mustBefore).c_str(),
                    pct(r.moved).c_str(), pct(r.must).c_str(), pct(r.estimate35).c_str(),
                    pct(r.oracle35).c_str(), pct(r.estimate40).c_str(), pct(r.oracle40).c_str());
      count += 1;
      mean.spearman += r.spearman;
      mean.spearmanUnrounded += r.spearmanUnrounded;
      mean.ceiling += r.ceiling;
      mean.mustBefore += r.mustBefore;
      mean.moved += r.moved;
      mean.must += r.must;
      mean.estimate35 += r.estimate35;
      mean.oracle35 += r.oracle35;
      mean.estimate40 += r.estimate40;
      mean.oracle40 += r.oracle40;
    }
    if (!detailed && count > 0)
      std::printf("| %g | mean of %.0f | %.2f | %.2f | %.2f | %s | %s | %s | %s | %s | %s | %s |\n",
                  h, count, mean.spearman / count, mean.spearmanUnrounded / count,
                  mean.ceiling / count, pct(mean.mustBefore / count).c_str(),
                  pct(mean.moved / count).c_str(), pct(mean.must / count).c_str(),
                  pct(mean.estimate35 / count).c_str(), pct(mean.oracle35 / count).c_str(),
                  pct(mean.estimate40 / count).c_str(), pct(mean.oracle40 / count).c_str());
  }
  std::printf("\n**Where the plain frame's error lies** (against the traced frame): each way of "
              "predicting, its share of the pixels / of the squared error; for moved edges also "
              "the share of them whose centre shows another surface (object or ending) than the "
              "traced frame's, and their share of the moved edges' error; all of the frame a "
              "target is completed from (the preview hedges the shadow's rim):\n\n| h | M | "
              "preview vs traced | plain vs traced |");
  const PathMethod shown[] = { PathMethod::Cubic,       PathMethod::Quadratic,
                               PathMethod::Linear,      PathMethod::Retrace,
                               PathMethod::EdgeBlend,   PathMethod::MovedEdge,
                               PathMethod::MovedSurface };
  for (PathMethod m : shown)
    std::printf(" %s |", toString(m));
  std::printf(" moved: another surface |\n|---|---|---|---|");
  for (std::size_t k = 0; k <= std::size(shown); ++k)
    std::printf("---|");
  std::printf("\n");
  for (const PlainError& e : plainErrors)
  {
    std::printf("| %g | %.4f | %.1f dB | %.1f dB |", e.h, e.mass, e.previewPsnr, e.psnr);
    for (PathMethod m : shown)
      std::printf(" %s / %s |", pct(e.pixels[static_cast<std::size_t>(m)]).c_str(),
                  pct(e.error[static_cast<std::size_t>(m)]).c_str());
    std::printf(" %s / %s |\n", pct(e.movedOtherSurface).c_str(), pct(e.movedOtherError).c_str());
  }
  std::printf(
    "\n**The estimate's ranking within each way of predicting** (Spearman of the estimate "
    "against the error before rounding, against the traced frame, over the way's "
    "pixels; – where it has fewer than 16):\n\n| h | M |");
  const PathMethod ranked[] = { PathMethod::Cubic,     PathMethod::Quadratic,
                                PathMethod::Linear,    PathMethod::EdgeBlend,
                                PathMethod::MovedEdge, PathMethod::MovedSurface };
  for (PathMethod m : ranked)
    std::printf(" %s |", toString(m));
  std::printf("\n|---|---|");
  for (std::size_t k = 0; k < std::size(ranked); ++k)
    std::printf("---|");
  std::printf("\n");
  for (const PlainError& e : plainErrors)
  {
    std::printf("| %g | %.4f |", e.h, e.mass);
    for (PathMethod m : ranked)
    {
      const double r = e.rank[static_cast<std::size_t>(m)];
      if (std::isnan(r))
        std::printf(" – |");
      else
        std::printf(" %.2f |", r);
    }
    std::printf("\n");
  }
  // Where the traced frames spend their rays: a whole frame's anti-aliasing is spent on the pixels
  // its edges cross, and an interpolated frame whose edges all moved must trace those again.
  std::printf("\n**Where a traced frame's rays go** (the frames traced at each M with the keys' "
              "settings): the pixels anti-aliased (more than their centre ray), and the rays "
              "charged to them against every ray the frame integrated:\n\n| M | rays | "
              "anti-aliased pixels | their rays |\n|---|---|---|---|\n");
  for (const Frame& f : frames)
  {
    double pixels = 0, rays = 0;
    for (const RayRecord& r : f.traced)
      if (r.raysPerPixel > 1)
      {
        pixels += 1;
        rays += r.raysPerPixel;
      }
    std::printf("| %.4f | %.0f | %s | %s |\n", f.mass, f.rays,
                pct(pixels / static_cast<double>(f.traced.size())).c_str(),
                pct(f.rays > 0 ? rays / f.rays : 0.0).c_str());
  }
}
}

/// A plain preview sequence, as `asrt interpolate --method path -n N` makes it: N frames between
/// two keys of the mass ramp (keys h = 0.11 apart, 4 around), with the moved edges'
/// correspondences matched afresh for each frame and kept between frames (PathMatchCache); the
/// two are timed in turn, the fastest of 3 each, and their frames compared.
void runPreviewSequence()
{
  constexpr int kFrames = 8;
  constexpr double h = 0.11, first = 0.45;
  std::vector<std::vector<RayRecord>> records;
  std::vector<PathKey> path;
  for (int k = 0; k < 4; ++k)
    records.push_back(FrameTracer(rampScene(first + k * h)).traceRows(0, kSide));
  for (int k = 0; k < 4; ++k)
    path.push_back({ first + k * h, &records[static_cast<std::size_t>(k)] });
  const SceneDescription shading = rampScene(first + 1.5 * h);
  double fastest[2] = { 1e300, 1e300 };
  bool same = true;
  std::size_t made = 0;
  for (int repetition = 0; repetition < 3; ++repetition)
  {
    std::vector<PathFrame> frames[2];
    for (int kept = 0; kept < 2; ++kept)
    {
      PathOptions options;
      options.pointIndex = kdTreeIndexFactory();
      options.hedgeNearShadow = true;
      options.spacetimeAt = rampSpacetime();
      if (kept)
        options.matchCache = std::make_shared<PathMatchCache>();
      const double t0 = now();
      for (int f = 1; f <= kFrames; ++f)
        frames[kept].push_back(interpolateAlongPath(path, first + h + h * f / (kFrames + 1.0),
                                                    kSide, kSide, *shading.scene, options));
      fastest[kept] = std::min(fastest[kept], now() - t0);
      if (kept)
        made = options.matchCache->made();
    }
    for (int f = 0; f < kFrames; ++f)
      same = same && frames[0][f].estimate == frames[1][f].estimate &&
             frames[0][f].method == frames[1][f].method;
  }
  std::printf("\n**A preview sequence** (`runPreviewSequence`): %d frames between the keys M = "
              "%.2f and %.2f of the ramp (keys %.2f apart, 4 around), the plain preview: %.2f s "
              "a frame matching the keys afresh for each, %.2f s with the correspondences kept "
              "between frames (%zu matched in all, against %d), %.1f× faster; %s.\n",
              kFrames, first + h, first + 2 * h, h, fastest[0] / kFrames, fastest[1] / kFrames,
              made, 3 * kFrames, fastest[0] / fastest[1],
              same ? "the same frames" : "**the frames differ**");
}

int main()
{
  double load[3] = { 0, 0, 0 };
  if (getloadavg(load, 3) < 0)
    load[0] = -1;
  const double tStart = now();
  kSide = static_cast<int>(envNumber("ASRT_BENCH_PATH_SIDE", 200));
  kReferenceSide = static_cast<int>(envNumber("ASRT_BENCH_PATH_REFERENCE", 8));
  if (const char* preset = std::getenv("ASRT_BENCH_PATH_KEY_PRESET"))
    kKeyPreset = preset;
  const std::vector<BenchPath> paths = selectedPaths();
  std::printf("<!-- path:begin -->\n## Interpolation along a path, per pixel\n\n");
  std::printf("- **Machine:** %ld CPU(s), %d OpenMP threads, load average %.1f when the run "
              "started.\n",
              sysconf(_SC_NPROCESSORS_ONLN), omp_get_max_threads(), load[0]);
  std::printf("- **Regenerate:** `bench/run` (`ASRT_BENCH_ONLY=path`); it runs "
              "`build-bench/bin/asrt_bench_path` from the repository root.\n");
  if (envNumber("ASRT_BENCH_PATH_STUDY", 1) != 0)
  {
    runRampStudy(tStart);
    runPreviewSequence();
  }
  if (!paths.empty())
    printPaths(paths, static_cast<int>(envNumber("ASRT_BENCH_PATH_PATH_FRAMES", 4)),
               envList("ASRT_BENCH_PATH_PATH_TARGETS", { 30, 35, 40 }));
  std::printf("\nThe whole section took %.0f s.\n<!-- path:end -->\n", now() - tStart);
  return 0;
}
