// asrt interpolate: frames stored in PostgreSQL (two, or a chain of key frames) to the movie
// frames between them, by matching their rays (vtkGeodesicFrameInterpolator, one per consecutive
// pair), written as PNG and VTI sequences, a .pvd time series and a movie.
#include "Cli.h"

#include "DataFiles.h"
#include "MovieWriter.h"
#include "Progress.h"
#include "PvdCollection.h"
#include "VtkMessages.h"

#include "ErrorEstimate.h"
#include "PathInterpolation.h"
#include "vtkGeodesicFrameInterpolator.h"
#include "vtkGeodesicPathInterpolator.h"
#include "vtkGeodesicPostgreSQLReader.h"
#include "vtkGeodesicSource.h"

#include "vtkDataArray.h"
#include "vtkFieldData.h"
#include "vtkImageData.h"
#include "vtkNew.h"
#include "vtkPolyData.h"
#include "vtkSmartPointer.h"

#include <vtksys/SystemTools.hxx>

#include <algorithm>
#include <array>
#include <cstdio>
#include <functional>
#include <limits>
#include <memory>
#include <stdexcept>

namespace asrt
{
namespace cli
{
namespace
{
const char* const kHelp = R"(Usage: asrt interpolate A_ID B_ID [C_ID ...] [options]
       asrt interpolate --scenes A.json B.json [C.json ...] [options]

Makes the movie frames between two frames stored in PostgreSQL (asrt trace --store; asrt list
shows the ids) without tracing them again: rays of A and B that hit the same scene point are
matched, and every intermediate frame is drawn from the matched rays at the parameters of its
time t (mass, spin and charge linear in t; the camera on an orbit about the hole). A and B must be
whole frames of one scene at one resolution; they may differ in mass, spin, charge and camera.
Writes, for the N + 2 frames (t = 0 is A, t = 1 is B):
  PREFIX-000.png ...  the pictures
  PREFIX-000.vti ...  the frames as VTK image data, with InterpolationClass per pixel
  PREFIX.pvd          a ParaView time series of the .vti files (time = t)
  PREFIX.ogv          the movie (or the file --movie names)
and prints, per frame, the shares of its pixels that were matched, seen by one frame only,
filled as holes, ambiguous, or re-traced (--exact). The sequence is one set of files: everything
is checked (the frames, their sizes, in exact mode the scene's textures) before the first frame
is made, the files are written beside the previous ones under hidden temporary names, and they
all replace them in one last step; an error or Ctrl-C before it leaves the previous sequence as
it was. In that step the frames PREFIX-NNN.png and .vti of an earlier, longer sequence, numbered
beyond this one, are removed (no other file is touched).

More than two frames are key frames of one movie: N frames are made between each consecutive
pair and the sequence runs through every key frame (time k at key frame k). Interpolation is good
between close frames: accumulate key frames along a long ramp (asrt trace --sweep ... --store)
rather than interpolating its two ends.

Options:
  -n, --frames N        N intermediate frames between each pair (default 8; the paper's movie
                        between its two ends: 28)
  -o, --output PREFIX   where to write; a directory (an existing one, or ending in '/') gets
                        the name "interpolated": -o out/ gives out/interpolated-000.png
  --movie FILE          the movie's file: .ogv or .ogg (Ogg Theora), .mp4 (needs ffmpeg)
  --fps F               the movie's frames per second (default 10)
  --method M            how frames are made: "splats" (the default without --quality) moves
                        the key frames' rays across the picture, pair by pair (the paper's
                        method, a fast preview); "path" predicts every pixel from its own rays
                        in the nearest 4 key frames, cubic in the path's parameter (mass, spin,
                        charge or orbit angle), where they end alike
  --quality DB          with the path method (implied): re-trace, at each frame's parameters,
                        the pixels the key frames cannot vouch for and, worst estimated first,
                        enough others for the frame to reach DB against its converged picture
                        (4x4 samples a pixel); the key frames' own error against theirs is
                        measured first by a few probe pixels traced converged, and shown as
                        "settings"; where they fall short of DB, the pixels that hold their
                        error (the sampled edges first) are traced with the converged
                        rendering ("converged%")
  --against-traced      with --quality: hold the target against the frame traced at each
                        frame's parameters with the key frames' settings instead
  --keep-settings       with --quality: where the key frames' settings fall short of DB,
                        re-trace with them only (the frame then holds to about their bound,
                        with a warning) instead of tracing their error's pixels converged
  --exact               with splats: re-trace the pixels the matching cannot vouch for (holes,
                        ambiguous pixels, and those where A and B disagree); slower, exact there
  --textures DIR        where the scene's relative texture paths lie, for --exact and the
                        path method (default: the scenes directory, Data/scenes)
  -q, --quiet           no progress on stderr

Without the store:
  --scenes              the two arguments are scene files, traced first (nothing is stored)
  -r, --resolution WxH  with --scenes: the size of both frames (default: the scenes' own)
  --max-failed-share F  with --scenes: refuse a traced frame when more than this fraction of
                        its rays failed numerically or ran out of steps (default 0.05)
)";

const char* const kExamples = R"(
Examples:
  asrt trace Data/scenes/fig4-mass-start.json --store=ramp     (stored as frame 1)
  asrt trace Data/scenes/fig5-mass-end.json --store=ramp       (stored as frame 2)
  asrt interpolate 1 2 -n 28 -o movie/ --movie movie/mass-ramp.ogv
  asrt interpolate --scenes Data/scenes/fig4-mass-start.json Data/scenes/fig5-mass-end.json \
    -r 100x100 -n 28 -o movie/
)";

/// Key frames one command takes (each pair keeps its correspondence in memory).
constexpr std::size_t kMaxKeyFrames = 1000;

const char* const kClassNames[] = { "matched", "one-sided", "holes", "ambiguous", "re-traced" };

std::array<double, 5> fractions(vtkImageData* frame)
{
  std::array<double, 5> shares{};
  if (vtkDataArray* a = frame->GetFieldData()->GetArray("InterpolationFractions"))
    for (int k = 0; k < 5 && k < a->GetNumberOfComponents() * a->GetNumberOfTuples(); ++k)
      shares[k] = a->GetComponent(k / a->GetNumberOfComponents(), k % a->GetNumberOfComponents());
  return shares;
}

double fieldValue(vtkImageData* frame, const char* name)
{
  vtkDataArray* a = frame->GetFieldData()->GetArray(name);
  return a && a->GetNumberOfTuples() > 0 ? a->GetComponent(0, 0) : 0.0;
}

/// The key frames: traced from their scene files, or read from the store.
std::vector<vtkSmartPointer<vtkAlgorithm>> readKeyFrames(const Options& options,
                                                         const std::vector<std::string>& names,
                                                         bool fromScenes, bool quiet)
{
  const std::string conninfo = fromScenes ? std::string() : databaseConnection(options);
  std::vector<vtkSmartPointer<vtkAlgorithm>> ends(names.size());
  for (std::size_t k = 0; k < names.size(); ++k)
  {
    if (fromScenes)
    {
      auto source = vtkSmartPointer<vtkGeodesicSource>::New();
      setSceneFile(source, names[k]);
      if (const auto size = options.size("resolution"))
        source->SetResolution(size->first, size->second);
      traceFrame(source, "trace " + names[k], quiet);
      checkRayEnds(source->GetImageOutput(), maxFailedShare(options), names[k]);
      ends[k] = source;
      continue;
    }
    auto reader = vtkSmartPointer<vtkGeodesicPostgreSQLReader>::New();
    tools::VtkMessageCatcher messages;
    messages.watchAlgorithm(reader);
    reader->SetConnectionString(conninfo.c_str());
    limitReads(reader);
    reader->SetFrameId(static_cast<vtkIdType>(std::stoll(names[k])));
    reader->Update();
    if (tools::interruptRequested())
      throw Interrupted();
    if (messages.failed())
      throw DatabaseError(messages.firstError());
    ends[k] = reader;
  }
  return ends;
}

/// Where and how the sequence is written.
struct Sequence
{
  std::string prefix;
  int intermediate = 0;
  tools::AtomicFileSet* files = nullptr;
  tools::MovieWriter* movie = nullptr;
  tools::PvdCollection series;
  std::vector<std::string> lines; ///< each frame's shares of pixel classes
};

/// A frame of the sequence at `time` (key frame k at time k), its line of the table appended to
/// `line`; the frame stays valid until the next call.
using FrameAt = std::function<vtkImageData*(double time, std::string& line)>;

/// Writes every frame of the sequence into its set (nothing is in place before the set's
/// commit). `check` throws on an interrupt or a failed interpolation.
void writeFrames(int keyPairs, const FrameAt& frameAt, Sequence& out, tools::ProgressBar& bar,
                 const std::function<void()>& check)
{
  const int intermediate = out.intermediate;
  // Key frame k is frame k (N + 1) of the sequence; a key frame between two pairs is written once.
  const int count = keyPairs * (intermediate + 1) + 1;
  for (int k = 0; k < count; ++k)
  {
    const int pair = std::min(k / (intermediate + 1), keyPairs - 1);
    const double t = static_cast<double>(k - pair * (intermediate + 1)) / (intermediate + 1);
    const double time = pair + t;
    char head[64];
    std::snprintf(head, sizeof head, "%5d %7.4f", k, time);
    std::string line = head;
    vtkImageData* frame = frameAt(time, line);
    check();
    char number[32];
    std::snprintf(number, sizeof number, "-%03d", k);
    tools::writePng(frame, out.files->add(out.prefix + number + ".png"));
    tools::writeVti(frame, out.files->add(out.prefix + number + ".vti"));
    out.series.add(time, out.prefix + number + ".vti");
    out.movie->addFrame(frame);
    check();
    out.lines.push_back(line);
    bar.update(static_cast<double>(k + 1) / count);
  }
}

/// The splats' frames: one interpolator per consecutive pair of keys.
FrameAt splatFrames(const std::vector<vtkSmartPointer<vtkGeodesicFrameInterpolator>>& pairs)
{
  return [&pairs](double time, std::string& line)
  {
    const int pair = std::min(static_cast<int>(time), static_cast<int>(pairs.size()) - 1);
    vtkGeodesicFrameInterpolator* interpolator = pairs[static_cast<std::size_t>(pair)];
    interpolator->UpdateTimeStep(time - pair);
    vtkImageData* frame = interpolator->GetOutput();
    const std::array<double, 5> shares = fractions(frame);
    char text[160];
    std::snprintf(text, sizeof text, " %8.4g %9.1f %9.1f %9.1f %9.1f %9.1f",
                  fieldValue(frame, "Mass"), 100 * shares[0], 100 * shares[1], 100 * shares[2],
                  100 * shares[3], 100 * shares[4]);
    line += text;
    return frame;
  };
}

/// The path's frames: one interpolator over every key.
FrameAt pathFrames(vtkGeodesicPathInterpolator* path, bool target)
{
  return [path, target](double time, std::string& line)
  {
    path->UpdateTimeStep(time);
    vtkImageData* frame = path->GetOutput();
    double shares[kPathMethodCount] = {};
    if (vtkDataArray* a = frame->GetFieldData()->GetArray("PathMethodFractions"))
      for (int c = 0; c < kPathMethodCount && c < a->GetNumberOfComponents(); ++c)
        shares[c] = a->GetComponent(0, c);
    char text[200];
    std::snprintf(text, sizeof text, " %10.6g", fieldValue(frame, "PathParameter"));
    line += text;
    for (double share : shares)
    {
      std::snprintf(text, sizeof text, " %9.1f", 100 * share);
      line += text;
    }
    for (const char* name : { "EstimatedPsnr", "SettingsPsnr" })
    {
      if (!target)
        break;
      std::snprintf(text, sizeof text, " %9.1f",
                    frame->GetFieldData()->GetArray(name)
                      ? fieldValue(frame, name)
                      : std::numeric_limits<double>::infinity());
      line += text;
    }
    if (target)
    {
      int dims[3];
      frame->GetDimensions(dims);
      const double pixels = static_cast<double>(dims[0]) * dims[1];
      const double converged = frame->GetFieldData()->GetArray("ConvergedPixels")
                                 ? fieldValue(frame, "ConvergedPixels")
                                 : 0.0;
      std::snprintf(text, sizeof text, " %9.1f", pixels > 0 ? 100 * converged / pixels : 0.0);
      line += text;
    }
    return frame;
  };
}
}

int runInterpolate(const std::vector<std::string>& args)
{
  const Options options(std::vector<OptionSpec>{ { "frames", OptionSpec::Value, 'n' },
                                                 { "output", OptionSpec::Value, 'o' },
                                                 { "movie", OptionSpec::Value },
                                                 { "fps", OptionSpec::Value },
                                                 { "exact", OptionSpec::Flag },
                                                 { "method", OptionSpec::Value },
                                                 { "quality", OptionSpec::Value },
                                                 { "against-traced", OptionSpec::Flag },
                                                 { "keep-settings", OptionSpec::Flag },
                                                 { "textures", OptionSpec::Value },
                                                 { "quiet", OptionSpec::Flag, 'q' },
                                                 { "scenes", OptionSpec::Flag },
                                                 { "resolution", OptionSpec::Value, 'r' },
                                                 { "max-failed-share", OptionSpec::Value } } +
                          databaseSpecs(),
                        args);
  if (options.help())
  {
    std::printf("%s\n%s%s\n%s", kHelp, kDatabaseHelp, kExamples, kExitCodeHelp);
    return kOk;
  }
  const bool fromScenes = options.has("scenes");
  options.expectPositional(
    2, kMaxKeyFrames,
    fromScenes ? "at least two scene files (asrt interpolate --scenes A.json B.json [C.json ...])"
               : "at least two frame ids (asrt interpolate A_ID B_ID [C_ID ...])");
  if (options.has("resolution") && !fromScenes)
    throw UsageError("--resolution only goes with --scenes (stored frames keep their size)");
  const std::size_t keys = options.positional().size();
  std::vector<std::string> names(keys);
  for (std::size_t k = 0; k < keys; ++k)
    names[k] =
      fromScenes ? options.positional()[k] : std::to_string(parseFrameId(options.positional()[k]));
  const int intermediate = options.positiveInteger("frames").value_or(8);
  if (intermediate > vtkGeodesicFrameInterpolator::kMaxIntermediateFrames)
    throw UsageError("--frames: at most " +
                     std::to_string(vtkGeodesicFrameInterpolator::kMaxIntermediateFrames));
  const std::string method = options.get("method", options.has("quality") ? "path" : "splats");
  if (method != "splats" && method != "path")
    throw UsageError("--method: \"" + printable(method) + "\" is neither splats nor path");
  const bool path = method == "path";
  if (path && options.has("exact"))
    throw UsageError("--exact goes with --method splats; the path method re-traces with --quality");
  double quality = 0.0;
  if (options.has("quality"))
  {
    if (!path)
      throw UsageError("--quality goes with --method path");
    quality = parseNumber("--quality", options.get("quality"));
    if (!(quality > 0.0 && quality <= asrt::kMaxQualityTargetDb))
      throw UsageError("--quality: the target must lie in (0, 100] dB, got " +
                       options.get("quality"));
  }
  if (options.has("against-traced") && !options.has("quality"))
    throw UsageError("--against-traced goes with --quality");
  if (options.has("keep-settings") && !options.has("quality"))
    throw UsageError("--keep-settings goes with --quality");
  const int fps = options.positiveInteger("fps").value_or(10);
  const std::string prefix = outputPrefix(options, "interpolated");
  const std::string moviePath = options.get("movie", prefix + ".ogv");
  // The whole sequence is one set of files: its frames, .pvd and movie appear together when it
  // is committed, or not at all (an error or Ctrl-C before leaves the previous sequence as it
  // was). Declared before the movie, which is a member of it.
  tools::AtomicFileSet files;
  // The movie's format and rate are checked before any work is done.
  std::unique_ptr<tools::MovieWriter> movie;
  try
  {
    movie = std::make_unique<tools::MovieWriter>(moviePath, fps, &files);
  }
  catch (const std::invalid_argument& e)
  {
    throw UsageError(std::string("--movie/--fps: ") + e.what());
  }
  const bool quiet = options.has("quiet");
  const std::vector<vtkSmartPointer<vtkAlgorithm>> ends =
    readKeyFrames(options, names, fromScenes, quiet);

  // One interpolator per consecutive pair, each checked (same scene, same size, in exact mode the
  // scene's textures) before any frame is written.
  tools::VtkMessageCatcher messages;
  // Everything the readers returned is valid; what fails here is a pair itself (different
  // scenes or resolutions) or, in exact mode, the re-tracing of the scene.
  auto check = [&messages]()
  {
    if (tools::interruptRequested())
      throw Interrupted();
    if (messages.failed())
      throw InputError(messages.firstError());
  };
  std::vector<vtkSmartPointer<vtkGeodesicFrameInterpolator>> pairs;
  vtkNew<vtkGeodesicPathInterpolator> along;
  std::string chain = names[0];
  for (std::size_t k = 1; k < keys; ++k)
    chain += " -> " + names[k];
  if (path)
  {
    for (std::size_t k = 0; k < keys; ++k)
      along->AddKeyFrameConnection(ends[k]->GetOutputPort(1));
    along->SetNumberOfIntermediateFrames(intermediate);
    along->SetQualityTarget(quality);
    along->SetHoldToConverged(!options.has("against-traced"));
    along->SetRaiseRenderingForTarget(!options.has("keep-settings"));
    along->SetTextureDirectory(options.get("textures", scenesDirectory()).c_str());
    messages.watchAlgorithm(along);
    along->UpdateInformation();
    check();
  }
  for (std::size_t k = 0; !path && k + 1 < keys; ++k)
  {
    auto interpolator = vtkSmartPointer<vtkGeodesicFrameInterpolator>::New();
    interpolator->SetFrameAConnection(ends[k]->GetOutputPort(1));
    interpolator->SetFrameBConnection(ends[k + 1]->GetOutputPort(1));
    interpolator->SetNumberOfIntermediateFrames(intermediate);
    interpolator->SetExactMode(options.has("exact"));
    interpolator->SetTextureDirectory(options.get("textures", scenesDirectory()).c_str());
    messages.watchAlgorithm(interpolator);
    interpolator->UpdateInformation();
    check();
    pairs.push_back(interpolator);
  }

  const int keyPairs = static_cast<int>(keys) - 1;
  const int count = keyPairs * (intermediate + 1) + 1;
  tools::ProgressBar bar("interpolate " + chain, quiet ? tools::ProgressBar::Style::Silent
                                                       : tools::ProgressBar::Style::Automatic);
  Sequence sequence;
  sequence.prefix = prefix;
  sequence.intermediate = intermediate;
  sequence.files = &files;
  sequence.movie = movie.get();
  writeFrames(keyPairs, path ? pathFrames(along, quality > 0.0) : splatFrames(pairs), sequence, bar,
              check);
  sequence.series.write(files.add(prefix + ".pvd"));
  movie->close();
  // Frames of an earlier, longer sequence would look like part of this one: they go in the
  // same commit.
  std::vector<std::string> stale = staleFrames(prefix, count);
  stale.erase(std::remove(stale.begin(), stale.end(), moviePath), stale.end());
  for (const std::string& path : stale)
    files.remove(path);
  check();
  files.commit();
  bar.finish("-> " + prefix + "-*.png");

  std::string mode = options.has("exact") ? ", exact mode" : "";
  if (path)
    mode = ", per pixel along the " + std::string(along->GetPathParameterName()) +
           (quality > 0.0 ? ", quality target " + options.get("quality") + " dB"
                          : ", nothing re-traced");
  std::printf("%s %s: %d frames (%d intermediate%s)%s\n", fromScenes ? "scenes" : "frames",
              printable(chain).c_str(), count, intermediate, keys > 2 ? " between each pair" : "",
              mode.c_str());
  if (path)
  {
    std::printf("%5s %7s %10s", "frame", "time", along->GetPathParameterName());
    for (int m = 0; m < kPathMethodCount; ++m)
      std::printf(" %8s%%", toString(static_cast<PathMethod>(m)));
    if (quality > 0.0)
      std::printf(" %9s %9s %9s", "est. PSNR", "settings", "converged%");
  }
  else
  {
    std::printf("%5s %7s %8s", "frame", "time", "M");
    for (const char* name : kClassNames)
      std::printf(" %8s%%", name);
  }
  std::printf("\n");
  for (const std::string& line : sequence.lines)
    std::printf("%s\n", line.c_str());
  // The filters' warnings (a target above what the keys' settings reach, with --keep-settings),
  // each said once, however many frames repeated it.
  std::vector<std::string> said;
  for (const std::string& w : messages.warnings())
    if (std::find(said.begin(), said.end(), w) == said.end())
    {
      said.push_back(w);
      std::fprintf(stderr, "asrt interpolate: warning: %s\n", w.c_str());
    }
  std::printf("  wrote %s-%03d.png ... %s-%03d.png (and .vti)\n", prefix.c_str(), 0, prefix.c_str(),
              count - 1);
  std::printf("  wrote %s (ParaView time series of %d frames)\n", (prefix + ".pvd").c_str(), count);
  std::printf("  wrote %s (%d frames at %d per second)\n", moviePath.c_str(), count, fps);
  if (!stale.empty())
    std::printf("  removed %zu files of an earlier, longer sequence (%s-%03d.* on)\n", stale.size(),
                prefix.c_str(), count);
  return kOk;
}
}
}
