// asrt movie: a movie along a path (a ramp of mass, spin or charge, or an orbit of the camera) at
// a quality target, for as few traced rays as the plan (MoviePlan.h) can manage: key frames
// traced whole, the others interpolated per pixel between them (PathInterpolation.h) with the
// pixels the target needs re-traced, or traced whole where that is cheaper. With --store, every
// whole frame and every re-traced subset of pixels is accumulated in PostgreSQL, and whatever is
// stored already is read instead of traced.
//
// Reuse. A whole frame is found by its identity (the scene at the frame's parameters), whoever
// stored it (asrt trace --store, --sweep, --orbit: the same parameters give the same identity).
// The pixels an interpolated frame re-traces are stored as subset frames, as the splat
// interpolator's StoreRetracedRays does: the scene at the frame's parameters with a "subset"
// naming the pixels (count and digest), so they never pass for the whole frame. completePathFrame
// asks for two lists of pixels, each a function of the keys and of the records traced before; the
// same keys therefore ask for the same lists, which the store then has. The plan is stable under
// storing its own whole frames (MoviePlan.h), so running the same movie again has the same keys:
// it traces nothing and writes the same bytes.
#include "Cli.h"

#include "AtomicFile.h"
#include "CameraOrbit.h"
#include "CameraPath.h"
#include "DataFiles.h"
#include "MovieWriter.h"
#include "Progress.h"
#include "PvdCollection.h"
#include "VtkMessages.h"

#include "ErrorEstimate.h"
#include "FrameTracer.h"
#include "GeodesicRecordArrays.h"
#include "GeodesicSceneLoading.h"
#include "MoviePlan.h"
#include "PathInterpolation.h"
#include "RayStore.h"
#include "SceneFile.h"
#include "vtkGeodesicSource.h"

#include "vtkImageData.h"
#include "vtkNew.h"

#include <vtksys/SystemTools.hxx>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <optional>

namespace asrt
{
namespace cli
{
namespace
{
const char* const kHelp =
  R"(Usage: asrt movie SCENE.json (--ramp P=FROM:TO | --orbit DEGREES | --cameras FILE) [options]

Makes a movie of FRAMES frames along a path, each meeting a quality target (its estimated PSNR
against the frame traced at its parameters), for as few traced rays as a plan can manage: some
frames are traced whole as key frames, the others are interpolated per pixel between the nearest
key frames (asrt interpolate --method path) with just the pixels the target needs re-traced, or
traced whole where the plan estimates that cheaper. The plan's estimate of the share an
interpolated frame re-traces is proportional to its keys' spacing; it never plans more rays than
tracing every frame. Writes, for frames 0 ... FRAMES - 1,
  PREFIX-000.png ...  the pictures
  PREFIX-000.vti ...  the frames as VTK image data
  PREFIX.pvd          a ParaView time series of the .vti files (time = frame number)
  PREFIX.ogv          the movie (or the file --movie names)
as one set of files: an error or Ctrl-C before the end leaves the previous set as it was (the
frames PREFIX-NNN.png and .vti of an earlier, longer movie, numbered beyond this one, go in the
same step). Then
prints a table: per frame its method (key, traced, interpolated, reused), its estimated PSNR and
the share of its pixels re-traced, and the rays traced against tracing every frame.

With --store, every frame traced whole and every set of pixels re-traced is accumulated in
PostgreSQL, and whatever is stored already is read instead of traced (whole frames whoever stored
them: asrt trace --store with --sweep or --orbit of the same frame count stores the same frames).
Running the same movie again traces nothing and writes the same bytes.

The path (one of):
  --ramp P=FROM:TO      P (mass, spin or charge) from FROM to TO, frame k at
                        FROM + (TO - FROM) k / (FRAMES - 1) (as asrt trace --sweep P=FROM:TO:FRAMES)
  --orbit DEGREES       the camera (eye, focal point and up) turned about the hole's axis (z)
                        through DEGREES (as asrt trace --orbit FRAMES:DEGREES; 360 is a closed
                        orbit whose last frame is one step short of the first)
  --cameras FILE        the camera through key cameras, a JSON file {"keys": [{"position":
                        [x, y, z], "focalPoint": [x, y, z], "viewUp": [x, y, z]}, ...]} of two
                        or more keys: eye, focal point and view-up each on the Catmull-Rom
                        spline through the keys, frame k at key (K - 1) k / (FRAMES - 1)

Options:
  -n, --frames N        frames of the movie, at least 2 (default 24)
  --quality DB          the PSNR every interpolated frame is to reach, in (0, 100] (default 35)
  --fps F               the movie's frames per second (default 24)
  -o, --output PREFIX   where to write; a directory (an existing one, or ending in '/') gets the
                        scene's file name: -o out/ gives out/fig4-mass-start-000.png
  --movie FILE          the movie's file: .ogv or .ogg (Ogg Theora), .mp4 (needs ffmpeg)
  --plan                print the plan and its estimated cost, trace and write nothing
  --store[=LABEL]       accumulate in PostgreSQL and reuse what is stored (label of new frames)
  -q, --quiet           no progress on stderr
)";

const char* const kExamples = R"(
Examples:
  asrt movie Data/scenes/fig4-mass-start.json --ramp mass=0.1:1.2 -n 30 -r 200x200 -o ramp/
  asrt movie Data/scenes/fig1-cylinders.json --orbit 90 -n 24 -r 200x200 --store -o orbit/
  asrt movie Data/scenes/kerr-disk.json --ramp spin=0:0.99 -n 24 --quality 40 --store --plan
  asrt movie Data/scenes/fig1-cylinders.json --cameras flight.json -n 48 -r 200x200 -o flight/
)";

constexpr int kMaxMovieFrames = 10000;
/// The prior of the re-trace share (SpacingShareModel): a quarter of a frame re-traced, beyond the
/// probes, between keys a quarter of the path apart. The paper's mass ramp re-traced 23 % in
/// exact mode with keys ΔM = 0.2 apart on M 0.1 → 1.2 (README, "Interpolated movies").
constexpr double kPriorSlope = 1.0;
/// completePathFrame's default probe share, the floor of the estimate.
constexpr double kProbeFraction = 0.01;

/// One frame of the movie: where it lies on the path and which scene it is.
struct MovieFrame
{
  double s = 0;
  std::string describe;
  std::string sceneText;     ///< the effective scene text at the frame's parameters
  SceneDescription identity; ///< without textures: the frame's identity in the store
  std::optional<std::int64_t> storedId;
};

/// The path: a setting of the source per frame, and its parameter.
struct PathFrames
{
  std::string parameter; ///< "mass", "spin", "charge" or "orbit angle"
  std::vector<double> s;
  std::vector<std::function<void(vtkGeodesicSource*)>> apply;
};

std::string formatNumber(double v)
{
  char text[32];
  std::snprintf(text, sizeof text, "%.6g", v);
  return text;
}

PathFrames rampPath(const std::string& spec, int n)
{
  const std::size_t eq = spec.find('=');
  const std::string parameter = spec.substr(0, eq);
  if (eq == std::string::npos)
    throw UsageError("--ramp: expected P=FROM:TO with P mass, spin or charge, got " +
                     quotedArgument(spec));
  if (parameter != "mass" && parameter != "spin" && parameter != "charge")
    throw UsageError("--ramp: unknown parameter " + quotedArgument(parameter) +
                     " (mass, spin or charge)");
  const std::string range = spec.substr(eq + 1);
  const std::size_t colon = range.find(':');
  if (colon == std::string::npos || range.find(':', colon + 1) != std::string::npos)
    throw UsageError("--ramp: expected " + parameter + "=FROM:TO, got " + quotedArgument(spec));
  const double from = parseNumber("--ramp", range.substr(0, colon));
  const double to = parseNumber("--ramp", range.substr(colon + 1));
  if (from == to)
    throw UsageError("--ramp: FROM and TO are equal (" + formatNumber(from) + "): no path");
  PathFrames path;
  path.parameter = parameter;
  for (int k = 0; k < n; ++k)
  {
    // The formula of asrt trace --sweep, so that its frames are these frames.
    const double v = from + (to - from) * k / (n - 1);
    path.s.push_back(v);
    path.apply.push_back(
      [parameter, v](vtkGeodesicSource* src)
      {
        if (parameter == "mass")
          src->SetMass(v);
        else if (parameter == "spin")
          src->SetSpin(v);
        else
          src->SetCharge(v);
      });
  }
  return path;
}

PathFrames orbitPath(const std::string& spec, int n, const std::string& sceneText,
                     const Options& options)
{
  const double degrees = parseNumber("--orbit", spec);
  if (degrees == 0 || std::abs(degrees) > 360)
    throw UsageError("--orbit: DEGREES must be nonzero and at most 360 in magnitude, got " +
                     quotedArgument(spec));
  tools::CameraPose pose = tools::sceneCameraOfText(sceneText);
  auto override = [&options](const char* name, Vec3& v)
  {
    if (auto given = options.vector3(name))
      v = Vec3((*given)[0], (*given)[1], (*given)[2]);
  };
  override("camera", pose.position);
  override("focal", pose.focalPoint);
  override("view-up", pose.viewUp);
  PathFrames path;
  path.parameter = "orbit angle";
  for (int k = 0; k < n; ++k)
  {
    const double angle = tools::orbitAngle(k, n, degrees);
    const tools::CameraPose turned = tools::turnedAboutZ(pose, angle);
    path.s.push_back(angle);
    path.apply.push_back([turned](vtkGeodesicSource* src) { tools::setCamera(src, turned); });
  }
  return path;
}

PathFrames cameraPath(const std::string& file, int n)
{
  const std::vector<tools::CameraPose> keys = tools::parseCameraKeys(readSceneFile(file), file);
  PathFrames path;
  path.parameter = "camera key";
  const double last = static_cast<double>(keys.size() - 1);
  for (int k = 0; k < n; ++k)
  {
    // Frame k at u = (K - 1) k / (n - 1): the keys at u = 0 ... K - 1, the first and last frames
    // the first and last keys.
    const double u = last * k / (n - 1);
    const tools::CameraPose pose = tools::cameraOnPath(keys, u);
    path.s.push_back(u);
    path.apply.push_back([pose](vtkGeodesicSource* src) { tools::setCamera(src, pose); });
  }
  return path;
}

/// The frames' scenes, each checked (a camera sent inside the horizon, a spin ramped past the
/// mass) before anything is traced.
std::vector<MovieFrame> movieFrames(vtkGeodesicSource* source, const PathFrames& path)
{
  std::vector<MovieFrame> frames(path.s.size());
  for (std::size_t k = 0; k < frames.size(); ++k)
  {
    MovieFrame& f = frames[k];
    f.s = path.s[k];
    f.describe = path.parameter + " = " + formatNumber(f.s);
    path.apply[k](source);
    tools::VtkMessageCatcher messages;
    messages.watch(source);
    f.sceneText = source->GetFrameSceneText();
    if (messages.failed() || f.sceneText.empty())
      throw InputError("frame " + std::to_string(k) + " (" + f.describe +
                       "): " + messages.firstError());
    f.identity = parseSceneWithoutImages(f.sceneText);
  }
  return frames;
}

/// Everything a run shares: the frames, the store, the counts.
struct MovieRun
{
  std::vector<MovieFrame> frames;
  std::string textureDirectory;
  std::unique_ptr<RayStore> store;
  std::string label;
  double maxFailedShare = kDefaultMaxFailedShare;
  int width = 0, height = 0;
  std::map<int, std::vector<RayRecord>> wholeFrames; ///< the keys' records, in pixel order
  double raysTraced = 0;                             ///< this run
  double raysOfMovie = 0; ///< traced now or read from the store: what the movie cost in all
  double raysOfKeys = 0;  ///< of the whole frames, traced or read
  int wholeCount = 0;
};

double raysOf(const std::vector<RayRecord>& records)
{
  double rays = 0;
  for (const RayRecord& r : records)
    rays += r.raysPerPixel;
  return rays;
}

void stopIfInterrupted()
{
  if (tools::interruptRequested())
    throw Interrupted();
}

/// Stores a frame (whole or a subset). Another writer may have stored it since it was looked up:
/// then its copy stands.
void storeFrame(MovieRun& run, const SceneDescription& identity,
                const std::vector<RayRecord>& records, double seconds)
{
  try
  {
    run.store->writeFrame(
      identity, run.label, records,
      FrameWriteOptions().tracedIn(seconds).cancelledWhen(&tools::interruptRequested));
  }
  catch (const StoreError&)
  {
    stopIfInterrupted();
    if (!run.store->findFrame(identity))
      throw;
  }
}

SceneDescription sceneWithTextures(const MovieRun& run, const MovieFrame& f)
{
  return loadScene(f.sceneText.c_str(), nullptr, run.textureDirectory.c_str());
}

/// A whole frame's records, in pixel order: read from the store, or traced (and stored).
std::vector<RayRecord> wholeFrame(MovieRun& run, int k)
{
  const MovieFrame& f = run.frames[static_cast<std::size_t>(k)];
  std::vector<RayRecord> records;
  if (f.storedId)
  {
    records = run.store->readFrame(*f.storedId);
    std::sort(records.begin(), records.end(),
              [](const RayRecord& a, const RayRecord& b)
              { return a.j != b.j ? a.j < b.j : a.i < b.i; });
    if (records.size() != static_cast<std::size_t>(run.width) * run.height)
      throw DatabaseError("stored frame " + std::to_string(*f.storedId) + " has " +
                          std::to_string(records.size()) + " rays, the movie's frames " +
                          std::to_string(run.width * run.height) + " pixels");
  }
  else
  {
    const FrameTracer tracer(sceneWithTextures(run, f));
    const auto t0 = std::chrono::steady_clock::now();
    records = tracer.traceRows(0, run.height, [](double) { return !tools::interruptRequested(); });
    stopIfInterrupted();
    const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    vtkNew<vtkImageData> image;
    recordsToImage(records, run.width, 0, run.height, image);
    // A frame with too many failed rays is no picture of its scene: neither written nor stored.
    checkRayEnds(image, run.maxFailedShare, "frame " + std::to_string(k) + " (" + f.describe + ")");
    run.raysTraced += raysOf(records);
    if (run.store)
      storeFrame(run, f.identity, records, seconds);
  }
  run.raysOfMovie += raysOf(records);
  run.raysOfKeys += raysOf(records);
  ++run.wholeCount;
  return records;
}

/// What made one frame, for the table.
struct FrameReport
{
  FrameMethod method = FrameMethod::Key;
  double estimatedPsnr = std::numeric_limits<double>::infinity();
  double shareRetraced = 0;
  double raysTraced = 0;
  double raysReused = 0;
};

/// The re-traced pixels of interpolated frame k: read from the store when it has exactly that
/// subset at the frame's parameters, else traced (and stored).
PixelTracer retracedPixels(MovieRun& run, int k, const FrameTracer& tracer, FrameReport& report)
{
  return [&run, k, &tracer, &report](const std::vector<std::pair<int, int>>& pixels)
  {
    std::vector<RayRecord> records;
    if (pixels.empty())
      return records;
    SceneDescription subset = run.frames[static_cast<std::size_t>(k)].identity;
    subset.subset = pixelSubsetId(pixels);
    subset.rendering = scatteredPixelRendering(subset.rendering); // as the tracer traces them
    if (run.store)
      if (const auto id = run.store->findFrame(subset))
      {
        std::map<std::pair<int, int>, RayRecord> byPixel;
        for (const RayRecord& r : run.store->readFrame(*id))
          byPixel.emplace(std::make_pair(r.i, r.j), r);
        for (const auto& ij : pixels)
        {
          const auto found = byPixel.find(ij);
          if (found == byPixel.end())
            throw DatabaseError("stored subset frame " + std::to_string(*id) + " lacks pixel (" +
                                std::to_string(ij.first) + ", " + std::to_string(ij.second) +
                                ") that its digest names");
          records.push_back(found->second);
        }
        report.raysReused += raysOf(records);
        run.raysOfMovie += raysOf(records);
        return records;
      }
    const auto t0 = std::chrono::steady_clock::now();
    records = tracer.tracePixels(pixels, [](double) { return !tools::interruptRequested(); });
    stopIfInterrupted();
    const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    report.raysTraced += raysOf(records);
    run.raysTraced += raysOf(records);
    run.raysOfMovie += raysOf(records);
    if (run.store)
      storeFrame(run, subset, records, seconds);
    return records;
  };
}

/// Interpolated frame k between the plan's keys, completed to the target.
std::vector<RayRecord> interpolatedFrame(MovieRun& run, int k, const Scene& shading,
                                         double direction, double quality, FrameReport& report)
{
  std::vector<PathKey> keys;
  for (const auto& [key, records] : run.wholeFrames)
    keys.push_back({ direction * run.frames[static_cast<std::size_t>(key)].s, &records });
  const MovieFrame& f = run.frames[static_cast<std::size_t>(k)];
  PathFrame frame = interpolateAlongPath(keys, direction * f.s, run.width, run.height, shading);
  SceneDescription retrace = sceneWithTextures(run, f);
  retrace.rendering = scatteredPixelRendering(retrace.rendering);
  const FrameTracer tracer(retrace);
  const PathCompletion done =
    completePathFrame(frame, retracedPixels(run, k, tracer, report), quality, kProbeFraction);
  report.estimatedPsnr = done.estimatedPsnr;
  report.shareRetraced = static_cast<double>(done.retraced) / static_cast<double>(run.width) /
                         static_cast<double>(run.height);
  return std::move(frame.records);
}

std::string psnrText(double db)
{
  return std::isinf(db) ? std::string("exact") : formatNumber(std::round(db * 10) / 10);
}

void printPlan(const MoviePlan& plan, const std::vector<MovieFrame>& frames,
               const std::string& parameter)
{
  std::printf("%5s %12s %-13s %10s %12s\n", "frame", parameter.c_str(), "plan", "est.share%",
              "est.rays");
  for (std::size_t k = 0; k < frames.size(); ++k)
  {
    const FramePlan& f = plan.frames[k];
    std::string method = toString(f.method);
    if (f.method == FrameMethod::Interpolated)
      method += " " + std::to_string(f.keyBefore) + "-" + std::to_string(f.keyAfter);
    std::printf("%5zu %12.6g %-13s %10.1f %12.0f\n", k, frames[k].s, method.c_str(), 100 * f.share,
                f.rays);
  }
  std::printf("plan: %zu key frames (%zu of them stored already), estimated %.0f rays against "
              "%.0f tracing every frame not stored (%.2f of it)\n",
              plan.keys().size(),
              static_cast<std::size_t>(std::count_if(plan.frames.begin(), plan.frames.end(),
                                                     [](const FramePlan& f)
                                                     { return f.method == FrameMethod::Reused; })),
              plan.estimatedRays, plan.directRays,
              plan.directRays > 0 ? plan.estimatedRays / plan.directRays : 0.0);
}

/// The command line's movie settings, checked before anything is read or traced.
struct MovieSettings
{
  int count = 24;
  double quality = 35;
  int fps = 24;
  bool plan = false, quiet = false, store = false;
};

MovieSettings movieSettings(const Options& options)
{
  MovieSettings m;
  m.count = options.positiveInteger("frames").value_or(24);
  if (m.count < 2 || m.count > kMaxMovieFrames)
    throw UsageError("--frames: a movie has 2 to " + std::to_string(kMaxMovieFrames) +
                     " frames, got " + options.get("frames"));
  if (options.has("quality"))
  {
    const std::string text = options.get("quality");
    m.quality = parseNumber("--quality", text); // refuses NaN and infinities
    if (!(m.quality > 0.0 && m.quality <= kMaxQualityTargetDb))
      throw UsageError("--quality: the target must lie in (0, 100] dB, got " +
                       quotedArgument(text));
  }
  m.fps = options.positiveInteger("fps").value_or(24);
  m.plan = options.has("plan");
  m.quiet = options.has("quiet");
  m.store = options.has("store");
  if (options.has("ramp") + options.has("orbit") + options.has("cameras") != 1)
    throw UsageError("give one path: --ramp P=FROM:TO, --orbit DEGREES or --cameras FILE.json");
  return m;
}

/// Makes every frame and writes it into the set, in order; fills `reports`.
void makeFrames(MovieRun& run, const MoviePlan& plan, const Scene& shading,
                const MovieSettings& settings, tools::AtomicFileSet& files,
                tools::MovieWriter& movie, const std::string& prefix,
                std::vector<FrameReport>& reports)
{
  const int n = static_cast<int>(run.frames.size());
  const std::vector<int> keys = plan.keys();
  tools::ProgressBar bar("movie of " + std::to_string(n) + " frames",
                         settings.quiet ? tools::ProgressBar::Style::Silent
                                        : tools::ProgressBar::Style::Automatic);
  const double steps = static_cast<double>(keys.size() + static_cast<std::size_t>(n));
  double done = 0;
  for (int k : keys)
  {
    run.wholeFrames[k] = wholeFrame(run, k);
    bar.update(++done / steps);
  }
  const double direction = run.frames.back().s > run.frames.front().s ? 1.0 : -1.0;
  tools::PvdCollection series;
  reports.assign(run.frames.size(), FrameReport());
  for (int k = 0; k < n; ++k)
  {
    FrameReport& report = reports[static_cast<std::size_t>(k)];
    report.method = plan.frames[static_cast<std::size_t>(k)].method;
    std::vector<RayRecord> interpolated;
    const std::vector<RayRecord>* records = nullptr;
    if (report.method == FrameMethod::Interpolated)
    {
      interpolated = interpolatedFrame(run, k, shading, direction, settings.quality, report);
      records = &interpolated;
    }
    else
    {
      records = &run.wholeFrames.at(k);
      if (!run.frames[static_cast<std::size_t>(k)].storedId)
      {
        report.raysTraced = raysOf(*records);
        report.shareRetraced = 1;
      }
      else
        report.raysReused = raysOf(*records);
    }
    vtkNew<vtkImageData> image;
    recordsToImage(*records, run.width, 0, run.height, image);
    char number[32];
    std::snprintf(number, sizeof number, "-%03d", k);
    tools::writePng(image, files.add(prefix + number + ".png"));
    tools::writeVti(image, files.add(prefix + number + ".vti"));
    series.add(k, prefix + number + ".vti");
    movie.addFrame(image);
    stopIfInterrupted();
    bar.update(++done / steps);
  }
  series.write(files.add(prefix + ".pvd"));
  movie.close();
  // Frames of an earlier, longer movie at this prefix would look like part of this one.
  for (const std::string& path : staleFrames(prefix, n))
    files.remove(path);
  stopIfInterrupted();
  files.commit();
  bar.finish("-> " + prefix + "-*.png");
}

void printReport(const MovieRun& run, const MoviePlan& plan,
                 const std::vector<FrameReport>& reports, const std::string& parameter)
{
  std::printf("%5s %12s %-12s %9s %10s %12s %12s\n", "frame", parameter.c_str(), "method",
              "est.PSNR", "retraced%", "rays traced", "rays reused");
  for (std::size_t k = 0; k < reports.size(); ++k)
  {
    const FrameReport& r = reports[k];
    std::printf("%5zu %12.6g %-12s %9s %10.1f %12.0f %12.0f\n", k, run.frames[k].s,
                toString(r.method), psnrText(r.estimatedPsnr).c_str(), 100 * r.shareRetraced,
                r.raysTraced, r.raysReused);
  }
  // Tracing every frame: each as many rays as the whole frames took on average (measured).
  const double perFrame = run.wholeCount > 0 ? run.raysOfKeys / run.wholeCount : 0;
  const double direct = perFrame * static_cast<double>(reports.size());
  std::printf("rays traced: %.0f\n", run.raysTraced);
  std::printf("the movie's rays, traced now or before: %.0f; tracing every frame: %.0f "
              "(%.0f a frame, measured); ratio %.3f\n",
              run.raysOfMovie, direct, perFrame, direct > 0 ? run.raysOfMovie / direct : 0.0);
  // The plan counts a frame as its pixels (its decisions depend only on ratios); in measured
  // rays a frame, its estimate is:
  const double scale = perFrame / (static_cast<double>(run.width) * run.height);
  std::printf("the plan estimated %.0f rays against %.0f for tracing every frame not stored (at "
              "the measured rays a frame)\n",
              plan.estimatedRays * scale, plan.directRays * scale);
}
}

int runMovie(const std::vector<std::string>& args)
{
  const Options options(std::vector<OptionSpec>{ { "ramp", OptionSpec::Value },
                                                 { "orbit", OptionSpec::Value },
                                                 { "cameras", OptionSpec::Value },
                                                 { "frames", OptionSpec::Value, 'n' },
                                                 { "quality", OptionSpec::Value },
                                                 { "fps", OptionSpec::Value },
                                                 { "output", OptionSpec::Value, 'o' },
                                                 { "movie", OptionSpec::Value },
                                                 { "plan", OptionSpec::Flag },
                                                 { "store", OptionSpec::OptionalValue },
                                                 { "quiet", OptionSpec::Flag, 'q' } } +
                          sceneOverrideSpecs() + databaseSpecs(),
                        args);
  if (options.help())
  {
    std::printf("%s\n%s\n%s%s\n%s", kHelp, kDatabaseHelp, kSceneOverrideHelp, kExamples,
                kExitCodeHelp);
    return kOk;
  }
  options.expectPositional(1, 1, "the scene file (asrt movie SCENE.json --ramp mass=0.1:1.2)");
  const std::string scenePath = options.positional()[0];
  const MovieSettings settings = movieSettings(options);
  PathFrames path;
  if (options.has("ramp"))
  {
    path = rampPath(options.get("ramp"), settings.count);
    if (options.has(path.parameter))
      throw UsageError("--ramp " + path.parameter + " cannot be combined with --" + path.parameter);
  }

  vtkNew<vtkGeodesicSource> source;
  applySceneOverrides(options, source);
  setSceneFile(source, scenePath);
  if (options.has("orbit"))
    path = orbitPath(options.get("orbit"), settings.count, source->GetSceneText(), options);
  if (options.has("cameras"))
  {
    if (options.has("camera") || options.has("focal") || options.has("view-up"))
      throw UsageError("--cameras sets the camera of every frame: it cannot be combined with "
                       "--camera, --focal or --view-up");
    path = cameraPath(options.get("cameras"), settings.count);
  }

  // The movie's format and rate are checked before any work is done; the whole movie is one set.
  const std::string prefix = outputPrefix(options, scenePath);
  const std::string moviePath = options.get("movie", prefix + ".ogv");
  tools::AtomicFileSet files;
  std::unique_ptr<tools::MovieWriter> movie;
  try
  {
    movie = std::make_unique<tools::MovieWriter>(moviePath, settings.fps, &files);
  }
  catch (const std::invalid_argument& e)
  {
    throw UsageError(std::string("--movie/--fps: ") + e.what());
  }

  MovieRun run;
  run.frames = movieFrames(source, path);
  run.width = run.frames.front().identity.camera.width;
  run.height = run.frames.front().identity.camera.height;
  run.maxFailedShare = maxFailedShare(options);
  run.textureDirectory = vtksys::SystemTools::GetFilenamePath(scenePath);
  run.label = options.get("store");
  // Connect before tracing: an unreachable database should not cost a trace first.
  if (settings.store)
  {
    run.store = std::make_unique<RayStore>(databaseConnection(options));
    limitReads(*run.store);
    run.store->migrate();
  }
  std::vector<bool> stored(run.frames.size(), false);
  for (std::size_t k = 0; k < run.frames.size() && run.store; ++k)
  {
    run.frames[k].storedId = run.store->findFrame(run.frames[k].identity);
    stored[k] = run.frames[k].storedId.has_value();
  }
  SpacingShareModel share;
  share.pathLength = std::abs(path.s.back() - path.s.front());
  share.floor = std::min(1.0, std::max(kProbeFraction, 64.0 / (run.width * run.height)));
  share.slope = kPriorSlope;
  MovieCostModel model;
  model.frameRays = static_cast<double>(run.width) * run.height;
  model.retraceShare = share.function();
  const MoviePlan plan = planMovie(path.s, stored, model);
  if (settings.plan)
  {
    printPlan(plan, run.frames, path.parameter);
    return kOk;
  }

  const SceneDescription shading = sceneWithTextures(run, run.frames.front());
  std::vector<FrameReport> reports;
  try
  {
    makeFrames(run, plan, *shading.scene, settings, files, *movie, prefix, reports);
  }
  catch (const StoreError&)
  {
    // Ctrl-C cancels the store's statement under way: that is the interrupt, not the database.
    stopIfInterrupted();
    throw;
  }
  std::printf("movie of %zu frames along the %s, quality target %s dB%s\n", run.frames.size(),
              path.parameter.c_str(), formatNumber(settings.quality).c_str(),
              run.store ? ", accumulated in the store" : "");
  printReport(run, plan, reports, path.parameter);
  std::printf("  wrote %s-000.png ... %s-%03zu.png (and .vti), %s.pvd, %s\n", prefix.c_str(),
              prefix.c_str(), run.frames.size() - 1, prefix.c_str(), moviePath.c_str());
  return kOk;
}
}
}
