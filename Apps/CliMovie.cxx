// asrt movie: a movie along a path (a ramp of mass, spin or charge, an orbit of the camera, or a
// path through key cameras) at a quality target, for as few traced rays as the plan (MoviePlan.h)
// can manage. The movie itself is made by asrt::MovieMaker (GeodesicMovie.h), which
// vtkGeodesicMovieSource shares: key frames traced whole or read from the store, the others
// interpolated per pixel with the pixels the target needs re-traced, and with --store every
// whole frame and every re-traced subset accumulated in PostgreSQL and reused. This file reads
// the command line, writes the files as one set and prints the table.
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
#include "GeodesicMovie.h"
#include "GeodesicRecordArrays.h"
#include "MoviePlan.h"
#include "RayStore.h"
#include "vtkGeodesicSource.h"

#include "vtkImageData.h"
#include "vtkNew.h"

#include <vtksys/SystemTools.hxx>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>

namespace asrt
{
namespace cli
{
namespace
{
const char* const kHelp =
  R"(Usage: asrt movie SCENE.json (--ramp P=FROM:TO | --orbit DEGREES | --cameras FILE) [options]

Makes a movie of FRAMES frames along a path, each meeting a quality target (its estimated PSNR
against its converged picture, 4x4 samples a pixel; the key frames' own error against theirs is
measured by a few probe pixels traced converged, the "settings" column), for as few traced rays as a plan can manage: some
frames are traced whole as key frames, the others are interpolated per pixel between the nearest
key frames (asrt interpolate --method path) with just the pixels the target needs re-traced, or
traced whole where the plan estimates that cheaper. The plan's estimate of the share an
interpolated frame re-traces is proportional to its keys' spacing; it learns as the key frames
are made, coarse first: each is measured against its own interpolation (the share of pixels the
target needed, and the rays they took), and the frames not made yet are planned again. It never
plans more rays than tracing every frame. Writes, for frames 0 ... FRAMES - 1,
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
Running the same movie again traces nothing and writes the same bytes, from the pictures stored
with its frames (a frame whose keys were deleted since is made again); a movie with more frames
on the same path (2n - 1 after n) reads every old frame and traces only the new ones' pixels.

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
  --quality DB          the PSNR every interpolated frame is to reach, in (0, 100] (default 35);
                        with no rendering option, the rendering is chosen for it (measured on
                        the first and last frames): where the default does not reach it, 17
                        rays a pixel, else the accurate preset; where 5 rays a pixel reach it
                        with room to spare, 5 between the first and last frames
  --against-traced      hold the target against the frame traced at each frame's parameters
                        with the movie's settings, not against the converged picture
  --fps F               the movie's frames per second (default 24)
  -o, --output PREFIX   where to write; a directory (an existing one, or ending in '/') gets the
                        scene's file name: -o out/ gives out/fig4-mass-start-000.png
  --movie FILE          the movie's file: .ogv or .ogg (Ogg Theora), .mp4 (needs ffmpeg)
  --formats LIST        which of png,vti,movie to write (default: all three; vti brings the
                        .pvd with it)
  --plan                print the plan and its estimated cost, trace and write nothing (the
                        plan from the prior estimate: a run learns as it makes its keys)
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

std::string formatNumber(double v)
{
  char text[32];
  std::snprintf(text, sizeof text, "%.6g", v);
  return text;
}

MoviePath rampPath(const std::string& spec, int n)
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
  try
  {
    return rampMoviePath(parameter, from, to, n);
  }
  catch (const InvalidParameter& e)
  {
    throw UsageError(std::string("--") + e.what());
  }
}

MoviePath orbitPath(const std::string& spec, int n, const std::string& sceneText,
                    const Options& options)
{
  const double degrees = parseNumber("--orbit", spec);
  tools::CameraPose pose = tools::sceneCameraOfText(sceneText);
  auto override = [&options](const char* name, Vec3& v)
  {
    if (auto given = options.vector3(name))
      v = Vec3((*given)[0], (*given)[1], (*given)[2]);
  };
  override("camera", pose.position);
  override("focal", pose.focalPoint);
  override("view-up", pose.viewUp);
  try
  {
    return orbitMoviePath(pose, degrees, n);
  }
  catch (const InvalidParameter& e)
  {
    throw UsageError(std::string("--") + e.what());
  }
}

MoviePath cameraPath(const std::string& file, int n)
{
  return cameraKeyMoviePath(parseCameraKeys(readSceneFile(file), file), n);
}

void stopIfInterrupted()
{
  if (tools::interruptRequested())
    throw Interrupted();
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
struct MovieOptions
{
  int count = 24;
  double quality = 35;
  int fps = 24;
  bool plan = false, quiet = false, store = false;
  bool againstTraced = false;
  /// The outputs --formats names: the PNG frames, the VTI frames with their .pvd, the movie file.
  bool png = true, vti = true, movie = true;
};

/// --formats LIST: which of png, vti and movie to write.
void parseMovieFormats(const std::string& list, MovieOptions& m)
{
  const std::vector<bool> chosen = parseFormatList(list, { "png", "vti", "movie" });
  m.png = chosen[0];
  m.vti = chosen[1];
  m.movie = chosen[2];
}

MovieOptions movieOptions(const Options& options)
{
  MovieOptions m;
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
  if (options.has("formats"))
    parseMovieFormats(options.get("formats"), m);
  if (!m.movie && (options.has("movie") || options.has("fps")))
    throw UsageError(std::string(options.has("movie") ? "--movie" : "--fps") +
                     ": --formats leaves the movie file out");
  m.againstTraced = options.has("against-traced");
  m.plan = options.has("plan");
  m.quiet = options.has("quiet");
  m.store = options.has("store");
  if (options.has("ramp") + options.has("orbit") + options.has("cameras") != 1)
    throw UsageError("give one path: --ramp P=FROM:TO, --orbit DEGREES or --cameras FILE.json");
  return m;
}

/// The encodings of a frame's pictures stored with it, and their versions: a change to what
/// recordsToImage or the writers make of a frame takes a new version.
constexpr const char* kPngPicture = "png.1";
constexpr const char* kVtiPicture = "vti.1";

/// The pictures a movie's outputs are written from: the PNG for the PNG frames and the movie
/// file, the VTI for the VTI frames.
std::vector<std::string> pictureFormats(const MovieOptions& settings)
{
  std::vector<std::string> formats;
  if (settings.png || settings.movie)
    formats.push_back(kPngPicture);
  if (settings.vti)
    formats.push_back(kVtiPicture);
  return formats;
}

/// Makes every frame and writes it into the set, in order; fills `reports`. A frame whose
/// pictures an earlier run stored with it is written from them, nothing else of it read; the
/// others are made, and their pictures stored.
void makeFrames(MovieMaker& maker, const MovieOptions& settings, tools::AtomicFileSet& files,
                tools::MovieWriter* movie, const std::string& prefix,
                std::vector<MovieFrameReport>& reports)
{
  const int n = static_cast<int>(maker.frames().size());
  tools::ProgressBar bar("movie of " + std::to_string(n) + " frames",
                         settings.quiet ? tools::ProgressBar::Style::Silent
                                        : tools::ProgressBar::Style::Automatic);
  tools::FrameCount counted(n);
  bool keysMade = false;
  const auto makeKeys = [&]
  {
    maker.makeKeys([&](int k) { bar.update(counted.made(k)); });
    keysMade = true;
  };
  const std::vector<std::string> formats = pictureFormats(settings);
  const auto at = [&formats](const char* format)
  {
    return static_cast<std::size_t>(std::find(formats.begin(), formats.end(), format) -
                                    formats.begin());
  };
  tools::PvdCollection series;
  reports.assign(maker.frames().size(), MovieFrameReport());
  for (int k = 0; k < n; ++k)
  {
    MovieFrameReport& report = reports[static_cast<std::size_t>(k)];
    std::optional<std::vector<std::string>> pictures = maker.storedPictures(k, formats, report);
    if (!pictures && !keysMade)
    {
      makeKeys(); // then the pictures of whole frames traced are there too
      pictures = maker.storedPictures(k, formats, report);
    }
    vtkSmartPointer<vtkImageData> image;
    if (!pictures)
    {
      image = vtkSmartPointer<vtkImageData>::New();
      const int width = maker.width(), height = maker.height();
      maker.useFrame(k, report,
                     [width, height, &image](const std::vector<RayRecord>& records)
                     { recordsToImage(records, width, 0, height, image); });
    }
    char number[32];
    std::snprintf(number, sizeof number, "-%03d", k);
    std::vector<std::string> made(formats.size());
    if (settings.png)
    {
      tools::TemporaryFile& file = files.add(prefix + number + ".png");
      if (pictures)
        tools::writeBytes((*pictures)[at(kPngPicture)], file);
      else
        tools::writePng(image, file, &made[at(kPngPicture)]);
    }
    if (settings.vti)
    {
      tools::TemporaryFile& file = files.add(prefix + number + ".vti");
      if (pictures)
        tools::writeBytes((*pictures)[at(kVtiPicture)], file);
      else
        tools::writeVti(image, file, tools::kXmlCompression, &made[at(kVtiPicture)]);
      series.add(k, prefix + number + ".vti");
    }
    if (movie)
    {
      // The PNG's colours are the frame's: the movie is the same from either.
      if (pictures)
        image = tools::readPng((*pictures)[at(kPngPicture)]);
      movie->addFrame(image);
    }
    if (!pictures)
    {
      if (!settings.png) // the movie file's frames alone: their picture is stored all the same
        made[at(kPngPicture)] = tools::encodePng(image);
      maker.storePictures(k, formats, made, report);
    }
    stopIfInterrupted();
    bar.update(counted.made(k));
  }
  if (settings.vti)
    series.write(files.add(prefix + ".pvd"));
  if (movie)
    movie->close();
  // Frames of an earlier, longer movie at this prefix would look like part of this one.
  for (const std::string& path : staleFrames(prefix, n))
    files.remove(path);
  stopIfInterrupted();
  files.commit();
  bar.finish("-> " + prefix + (settings.png ? "-*.png" : settings.vti ? "-*.vti" : ""));
}

/// The line that says which rendering the movie was made with, where it was changed for the
/// target; `choosingRays` were traced to measure it (counted in the report's rays).
void printRenderingChoice(const RenderingChoice& choice, double quality, double choosingRays)
{
  using Change = RenderingChoice::Change;
  const std::string enough = formatNumber(quality + 1);
  if (choice.change == Change::Kept)
  {
    if (std::isfinite(choice.reach))
      std::printf("rendering: the default, which reaches %.1f dB against the converged picture "
                  "on the first and last frames; at most %d rays a pixel would reach %.1f there "
                  "(its probes' bound; %s needed)\n",
                  choice.defaultReach, kLoweredRaysPerPixel, choice.reach, enough.c_str());
    return;
  }
  if (choice.change == Change::Lowered)
    std::printf("rendering: at most %d rays a pixel between the first and last frames, since at "
                "that cap they reach %.1f dB against the converged picture (%s needed; the "
                "default: %.1f dB; %.0f rays traced for the two frames and the measures, counted "
                "below); --max-rays chooses another\n",
                kLoweredRaysPerPixel, choice.reach, enough.c_str(), choice.defaultReach,
                choosingRays);
  else if (choice.change == Change::Raised)
    std::printf("rendering: at most %d rays a pixel, since the default settings reach %.1f dB "
                "against the converged picture on the first and last frames and that cap %.1f "
                "(%s needed; %.0f rays traced to measure it, counted below); --max-rays or "
                "--preset chooses another\n",
                kRaisedRaysPerPixel, choice.defaultReach, choice.reach, enough.c_str(),
                choosingRays);
  else
    std::printf("rendering: the accurate preset, since the default settings reach %.1f dB "
                "against the converged picture on the first and last frames, and at most %d "
                "rays a pixel %.1f (%s needed; %.0f rays traced to measure it, counted below); "
                "--preset chooses another\n",
                choice.defaultReach, kRaisedRaysPerPixel, choice.reach, enough.c_str(),
                choosingRays);
}

/// `extraRays`: traced before this maker's movie (the first and last frames that measured the
/// default rendering's reach, when it was then `raised` to the accurate preset).
void printReport(MovieMaker& maker, const std::vector<MovieFrameReport>& reports, double quality,
                 double extraRays, bool raised)
{
  const MoviePlan& plan = maker.plan();
  std::printf("%5s %12s %-12s %9s %9s %10s %12s %12s\n", "frame", maker.parameter().c_str(),
              "method", "est.PSNR", "settings", "retraced%", "rays traced", "rays reused");
  for (std::size_t k = 0; k < reports.size(); ++k)
  {
    const MovieFrameReport& r = reports[k];
    std::printf("%5zu %12.6g %-12s %9s %9s %10.1f %12.0f %12.0f\n", k, maker.frames()[k].s,
                toString(r.method), psnrText(r.estimatedPsnr).c_str(),
                psnrText(r.settingsPsnr).c_str(), 100 * r.shareRetraced, r.raysTraced,
                r.raysReused);
  }
  // Tracing every frame: each as many rays as the whole frames took on average (measured).
  const double perFrame = maker.wholeCount() > 0 ? maker.raysOfKeys() / maker.wholeCount() : 0;
  const double direct = perFrame * static_cast<double>(reports.size());
  std::printf("rays traced: %.0f\n", maker.raysTraced() + extraRays);
  std::printf("the movie's rays, traced now or before: %.0f; tracing every frame: %.0f "
              "(%.0f a frame, measured); ratio %.3f\n",
              maker.raysOfMovie(), direct, perFrame,
              direct > 0 ? maker.raysOfMovie() / direct : 0.0);
  // The plan counts a frame as the rays it estimated (its pixels, until keys were measured); in
  // measured rays a frame, its estimate is:
  const double scale = plan.frameRays > 0 ? perFrame / plan.frameRays : 0.0;
  std::printf("the plan estimated %.0f rays against %.0f for tracing every frame not stored (at "
              "the measured rays a frame)\n",
              plan.estimatedRays * scale, plan.directRays * scale);
  // A target above what the keys' own settings reach against the converged picture cannot be met
  // by re-tracing with them: say so, and what raises them.
  double worstSettings = std::numeric_limits<double>::infinity();
  int below = 0;
  for (const MovieFrameReport& r : reports)
    if (r.method == FrameMethod::Interpolated && r.settingsPsnr < quality)
    {
      ++below;
      worstSettings = std::min(worstSettings, r.settingsPsnr);
    }
  if (below > 0)
    std::printf("note: for %d interpolated frames the key frames' settings reach less than the "
                "target against the converged picture (down to %.1f dB, their bound): those "
                "frames are held to within about 1 dB of it; %s raises it\n",
                below, worstSettings,
                raised ? "a --supersample" : "--preset accurate or a --supersample");
  const SpacingShareModel& share = maker.shareModel();
  if (!share.measurements.empty())
    std::printf("the plan learnt from %zu key frames: re-trace share %.3g + %.3g x key spacing / "
                "path; %.0f rays a whole frame (on average), interpolating one counted as %.0f\n",
                share.measurements.size(), share.floor, share.slope, plan.frameRays,
                plan.interpolationRays);
}

/// The options that choose a rendering: with any of them the movie keeps it.
const std::vector<const char*> kRenderingOptions = { "preset",      "antialias", "max-rays",
                                                     "supersample", "grid",      "grid-tolerance" };
}

int runMovie(const std::vector<std::string>& args)
{
  const Options options(std::vector<OptionSpec>{ { "ramp", OptionSpec::Value },
                                                 { "orbit", OptionSpec::Value },
                                                 { "cameras", OptionSpec::Value },
                                                 { "frames", OptionSpec::Value, 'n' },
                                                 { "quality", OptionSpec::Value },
                                                 { "against-traced", OptionSpec::Flag },
                                                 { "fps", OptionSpec::Value },
                                                 { "output", OptionSpec::Value, 'o' },
                                                 { "movie", OptionSpec::Value },
                                                 { "formats", OptionSpec::Value },
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
  const MovieOptions settings = movieOptions(options);
  MoviePath path;
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
    if (settings.movie)
      movie = std::make_unique<tools::MovieWriter>(moviePath, settings.fps, &files);
  }
  catch (const std::invalid_argument& e)
  {
    throw UsageError(std::string("--movie/--fps: ") + e.what());
  }

  const std::vector<MovieFrame> frames = movieFrames(source, path);
  // Connect before tracing: an unreachable database should not cost a trace first.
  std::unique_ptr<RayStore> store;
  if (settings.store)
  {
    store = std::make_unique<RayStore>(databaseConnection(options));
    limitReads(*store);
    store->migrate();
  }
  asrt::MovieSettings making;
  making.quality = settings.quality;
  making.holdToConverged = !settings.againstTraced;
  making.textureDirectory = vtksys::SystemTools::GetFilenamePath(scenePath);
  making.label = options.get("store");
  making.cancelled = &tools::interruptRequested;
  const double failedShare = maxFailedShare(options);
  making.checkTraced = [failedShare, &frames](const std::vector<RayRecord>& records, int k)
  {
    checkRayEnds(records, failedShare,
                 "frame " + std::to_string(k) + " (" +
                   frames[static_cast<std::size_t>(k)].describe + ")");
  };
  {
    // Each whole frame's pictures made when it is traced: its records are then let go without
    // being read back for them.
    making.pictureFormats = pictureFormats(settings);
    const int width = frames.front().identity.camera.width;
    const int height = frames.front().identity.camera.height;
    making.encodePictures =
      [width, height, formats = making.pictureFormats](const std::vector<RayRecord>& records)
    {
      vtkNew<vtkImageData> image;
      recordsToImage(records, width, 0, height, image);
      std::vector<std::string> bytes;
      for (const std::string& format : formats)
        bytes.push_back(format == kVtiPicture ? tools::encodeVti(image, tools::kXmlCompression)
                                              : tools::encodePng(image));
      return bytes;
    };
  }
  auto maker = std::make_unique<MovieMaker>(frames, path.parameter, store.get(), making);
  // When no rendering was asked for, the rendering is chosen for the target: a cheaper adaptive cap
  // where it reaches it, a dearer one or the accurate preset where the default does not
  // (MovieMaker::withRenderingForTarget).
  const bool renderingAsked =
    std::any_of(kRenderingOptions.begin(), kRenderingOptions.end(),
                [&options](const char* name) { return options.has(name); });
  const bool judged = !renderingAsked && maker->judgesRendering();
  double choosingRays = 0;
  RenderingChoice choice;
  std::vector<MovieFrameReport> reports;
  try
  {
    if (judged && !settings.plan)
      if (auto other = maker->withRenderingForTarget(source, path, choice))
      {
        choosingRays = maker->raysTraced();
        maker = std::move(other);
      }
    const MoviePlan& plan = maker->plan();
    if (settings.plan)
    {
      printPlan(plan, maker->frames(), path.parameter);
      if (judged)
        std::printf("rendering: the default, planned without tracing; the movie measures what it "
                    "reaches on the first and last frames: at %s dB or more, it is made at %d "
                    "rays a pixel where that reaches %s dB too; below, at %d where that does, "
                    "else with the accurate preset\n",
                    formatNumber(settings.quality + 1).c_str(), kLoweredRaysPerPixel,
                    formatNumber(settings.quality + 1).c_str(), kRaisedRaysPerPixel);
      return kOk;
    }
    makeFrames(*maker, settings, files, movie.get(), prefix, reports);
  }
  catch (const MovieCancelled&)
  {
    throw Interrupted();
  }
  catch (const StoreError&)
  {
    // Ctrl-C cancels the store's statement under way: that is the interrupt, not the database.
    stopIfInterrupted();
    throw;
  }
  std::printf("movie of %zu frames along the %s, quality target %s dB%s\n", frames.size(),
              path.parameter.c_str(), formatNumber(settings.quality).c_str(),
              store ? ", accumulated in the store" : "");
  printRenderingChoice(choice, settings.quality, choosingRays);
  printReport(*maker, reports, settings.quality, choosingRays,
              choice.change == RenderingChoice::Change::Raised ||
                choice.change == RenderingChoice::Change::Accurate);
  std::vector<std::string> wrote;
  char last[32];
  std::snprintf(last, sizeof last, "-%03zu", frames.size() - 1);
  if (settings.png)
    wrote.push_back(prefix + "-000.png ... " + prefix + last + ".png");
  if (settings.vti)
    wrote.push_back(prefix + "-000.vti ... " + prefix + last + ".vti, " + prefix + ".pvd");
  if (settings.movie)
    wrote.push_back(moviePath);
  std::string list;
  for (const std::string& w : wrote)
    list += (list.empty() ? "" : ", ") + w;
  std::printf("  wrote %s\n", list.c_str());
  return kOk;
}
}
}
