// asrt trace: a scene to PNG, VTI and VTP files, one frame or a series (a parameter sweep or an
// orbit of the camera) with ParaView .pvd collections, optionally stored in PostgreSQL.
#include "Cli.h"

#include "CameraOrbit.h"
#include "DataFiles.h"
#include "GeodesicMovie.h"
#include "Progress.h"
#include "PvdCollection.h"
#include "RayStore.h"
#include "SceneFile.h"
#include "VtkMessages.h"
#include "vtkGeodesicDistributedSource.h"
#include "vtkGeodesicPostgreSQLWriter.h"
#include "vtkGeodesicSource.h"

#include "vtkDoubleArray.h"
#include "vtkFieldData.h"
#include "vtkImageData.h"
#include "vtkInformation.h"
#include "vtkNew.h"
#include "vtkPolyData.h"
#include "vtkSmartPointer.h"
#include "vtkStreamingDemandDrivenPipeline.h"
#include "vtkStringArray.h"

#include <vtksys/SystemTools.hxx>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <memory>

namespace asrt
{
namespace cli
{
namespace
{
const char* const kHelp = R"(Usage: asrt trace SCENE.json [options]

Traces one light ray per pixel, backwards from the eye, through a scene (Data/scenes/ has the
paper's scenes; Data/scenes/README.md explains the format) and writes
  PREFIX.png        the picture
  PREFIX.vti        the frame as VTK image data: Colors, ObjectId, ImageOrder, PathLength and
                    Termination per pixel
  PREFIX-hits.vtp   one point per ray where it hit, with the ray's whole record (by default
                    only for frames of at most 1000000 pixels; see --formats)
  PREFIX-rays.vtp   with --polylines: the rays themselves (Lambda, R, AbsH along them)
ParaView opens the .vti and .vtp files. A series (--sweep or --orbit) numbers its files
PREFIX-000.png, PREFIX-001.png, ... and adds PREFIX.pvd, PREFIX-hits.pvd (and PREFIX-rays.pvd),
which ParaView opens as time series (time = frame number).

Output:
  -o, --output PREFIX   where to write; a directory (an existing one, or ending in '/')
                        gets the scene's file name: -o out/ gives out/fig1-cylinders.png
                        (default: the scene's file name in the current directory)
  --formats LIST        which of png,vti,vtp to write (default: png,vti,vtp for frames of
                        at most 1000000 pixels, png,vti above: the hit points of a 1920x1080
                        frame fill about 500 MB and take longer to write than the rest; name
                        vtp to have them at any size)
  --polylines[=STRIDE]  also write the rays as polylines, every STRIDE-th pixel in both
                        directions (default 10)
  -q, --quiet           no progress on stderr

A series (one of, at most 10000 frames):
  --sweep P=FROM:TO:N   N frames with P (mass, spin or charge) going from FROM to TO
  --orbit N[:DEGREES]   N frames with the camera (eye, focal point and up) turned about the
                        hole's axis (z) through DEGREES (default 360: a closed orbit, whose
                        last frame is one step short of the first; otherwise from 0 to DEGREES)

Storing (accumulation):
  --store[=LABEL]       also store every frame in PostgreSQL, with an optional label
  --replace             replace a stored frame with the same scene and parameters (storing
                        it again is an error otherwise)

Distributed (MPI): run as  mpirun -np N asrt trace SCENE.json --mpi [options]
  --mpi                 every process traces a share of the rows (on its own OpenMP threads:
                        set OMP_NUM_THREADS per process); with --store each streams its rows
                        to PostgreSQL as tiles of one frame, visible only once every tile is
                        in; process 0 assembles the frame and writes the files (png, vti; the
                        hits are in the store). The frame equals the single-process one bit
                        for bit. Prints the work of every process (integration steps, time).
  --mpi-split SPLIT     how rows are dealt: interleaved (row j to process j mod N, the
                        default: rays near the photon sphere cost far more, and interleaving
                        spreads them evenly), interleaved:K (blocks of K rows) or contiguous
                        (one band per process)
)";

const char* const kExamples = R"(
Examples:
  asrt trace Data/scenes/fig1-cylinders.json -o out/ -r 100x100
  asrt trace Data/scenes/fig1-cylinders.json --mass 0 --preset fast -o out/flat
  asrt trace Data/scenes/fig4-mass-start.json --sweep mass=0.1:1.2:12 -o out/ramp
  asrt trace Data/scenes/kerr-disk.json --orbit 8 -o out/orbit
  asrt trace Data/scenes/fig5-mass-end.json --store="mass ramp"
  OMP_NUM_THREADS=1 mpirun -np 4 asrt trace Data/scenes/kerr-disk.json -r 1920x1080 --mpi --store
)";

/// Frames a series may have (the settings of all of them are made before the first is traced).
constexpr int kMaxSeriesFrames = 10000;

/// The frame count N of a --sweep or --orbit; UsageError beyond kMaxSeriesFrames.
int seriesCount(const std::string& option, const std::string& text)
{
  const int n = parsePositiveInteger(option, text);
  if (n > kMaxSeriesFrames)
    throw UsageError(option + ": at most " + std::to_string(kMaxSeriesFrames) +
                     " frames in a series, got " + text);
  return n;
}

/// One frame of a series: what differs from the scene.
struct FrameSetting
{
  std::string describe; ///< e.g. "mass = 0.4"
  std::function<void(vtkGeodesicSource*)> apply;
};

std::string formatNumber(double v)
{
  char text[32];
  std::snprintf(text, sizeof text, "%.6g", v);
  return text;
}

std::vector<FrameSetting> sweepFrames(const std::string& spec)
{
  const std::size_t eq = spec.find('=');
  const std::string parameter = spec.substr(0, eq);
  if (eq == std::string::npos ||
      (parameter != "mass" && parameter != "spin" && parameter != "charge"))
    throw UsageError("--sweep: expected mass=FROM:TO:N (or spin=, charge=), got " +
                     quotedArgument(spec));
  const std::string range = spec.substr(eq + 1);
  const std::size_t c1 = range.find(':'), c2 = range.rfind(':');
  if (c1 == std::string::npos || c1 == c2)
    throw UsageError("--sweep: expected " + parameter + "=FROM:TO:N, got " + quotedArgument(spec));
  const double from = parseNumber("--sweep", range.substr(0, c1));
  const double to = parseNumber("--sweep", range.substr(c1 + 1, c2 - c1 - 1));
  const int n = seriesCount("--sweep", range.substr(c2 + 1));
  std::vector<FrameSetting> frames;
  for (int k = 0; k < n; ++k)
  {
    const double v = n == 1 ? from : from + (to - from) * k / (n - 1);
    frames.push_back({ parameter + " = " + formatNumber(v), [parameter, v](vtkGeodesicSource* s)
                       { setRampParameter(s, parameter, v); } });
  }
  return frames;
}

std::vector<FrameSetting> orbitFrames(const std::string& spec,
                                      const std::function<std::string()>& sceneText,
                                      const Options& options)
{
  const std::size_t colon = spec.find(':');
  const int n = seriesCount("--orbit", spec.substr(0, colon));
  const double degrees =
    colon == std::string::npos ? 360.0 : parseNumber("--orbit", spec.substr(colon + 1));
  // The camera to turn: the scene's, with the command line's overrides.
  tools::CameraPose pose = tools::sceneCameraOfText(sceneText());
  auto override = [&options](const char* name, Vec3& v)
  {
    if (auto given = options.vector3(name))
      v = Vec3((*given)[0], (*given)[1], (*given)[2]);
  };
  override("camera", pose.position);
  override("focal", pose.focalPoint);
  override("view-up", pose.viewUp);
  std::vector<FrameSetting> frames;
  for (int k = 0; k < n; ++k)
  {
    const double angle = tools::orbitAngle(k, n, degrees);
    const tools::CameraPose turned = tools::turnedAboutZ(pose, angle);
    frames.push_back({ "orbit " + formatNumber(angle) + " deg",
                       [turned](vtkGeodesicSource* s) { tools::setCamera(s, turned); } });
  }
  return frames;
}

double fieldValue(vtkPolyData* hits, const char* name, int component = 0)
{
  vtkDataArray* a = hits->GetFieldData()->GetArray(name);
  return a ? a->GetComponent(0, component) : std::nan("");
}

std::string fieldString(vtkPolyData* hits, const char* name)
{
  auto* a = vtkStringArray::SafeDownCast(hits->GetFieldData()->GetAbstractArray(name));
  return a && a->GetNumberOfValues() > 0 ? a->GetValue(0) : std::string();
}

/// Which files to write.
struct Formats
{
  bool png = false, vti = false, vtp = false;
  /// No list given: the hit points are written for frames of at most kHitsByDefaultPixels.
  bool vtpIfSmall = false;
};

/// The largest frame whose hit points are written without --formats naming vtp (1000×1000).
constexpr long long kHitsByDefaultPixels = 1000000;

Formats parseFormats(const std::string& list)
{
  const std::vector<bool> chosen = parseFormatList(list, { "png", "vti", "vtp" });
  Formats f;
  f.png = chosen[0];
  f.vti = chosen[1];
  f.vtp = chosen[2];
  return f;
}

/// The store's advice names its API; say what the command line offers instead (and nothing
/// where the store gives no such advice: a frame being written in tiles, a concurrent writer).
std::string withCommandLineAdvice(std::string why)
{
  const std::size_t api = why.find("; pass replace = true");
  if (api != std::string::npos)
    why = why.substr(0, api) + " (add --replace to store it again)";
  return why;
}

/// Refuses, before the trace, a frame that storing would refuse (already stored, without
/// --replace): the store's own identity check, on the scene the source is about to trace.
void refuseStoredFrame(RayStore& store, vtkGeodesicSource* source, bool replace)
{
  tools::VtkMessageCatcher messages;
  messages.watch(source);
  const std::string frameText = source->GetFrameSceneText();
  if (messages.failed())
    throw InputError(messages.firstError());
  try
  {
    store.checkFrameIdentity(parseSceneWithoutImages(frameText), replace);
  }
  catch (const StoreError& e)
  {
    if (tools::interruptRequested())
      throw Interrupted();
    throw DatabaseError(withCommandLineAdvice(e.what()));
  }
}

vtkIdType storeFrame(vtkPolyData* hits, const std::string& conninfo, const std::string& label,
                     bool replace)
{
  vtkNew<vtkGeodesicPostgreSQLWriter> writer;
  tools::VtkMessageCatcher messages;
  messages.watchAlgorithm(writer);
  writer->SetConnectionString(conninfo.c_str());
  writer->SetLabel(label.c_str());
  writer->SetReplaceExisting(replace);
  writer->SetInputData(hits);
  // Ctrl-C cancels the statement under way, a wait for a lock included; the frame rolls back.
  writer->SetCancelRequested(&tools::interruptRequested);
  if (tools::interruptRequested())
    throw Interrupted();
  writer->Write();
  if (messages.failed())
  {
    if (tools::interruptRequested())
      throw Interrupted();
    throw DatabaseError(withCommandLineAdvice(messages.firstError()));
  }
  return writer->GetFrameId();
}

void stopIfInterrupted()
{
  if (tools::interruptRequested())
    throw Interrupted();
}

/// Where the files of one frame go, and which of them there are.
struct FrameFiles
{
  std::string png, vti, hits, rays; ///< empty: not written
};

/// Writes a frame's files to their temporaries in `files` (none is in place before
/// files.commit()); an interrupt between two files stops with Interrupted, and the set then
/// removes them all.
FrameFiles writeFrameFiles(vtkGeodesicSource* source, const Formats& formats, bool polylines,
                           const std::string& base, tools::AtomicFileSet& files)
{
  FrameFiles names;
  stopIfInterrupted();
  int dims[3] = { 0, 0, 0 };
  source->GetImageOutput()->GetDimensions(dims);
  const bool hits =
    formats.vtp ||
    (formats.vtpIfSmall && static_cast<long long>(dims[0]) * dims[1] <= kHitsByDefaultPixels);
  // The PNG is encoded while the XML files are compressed. The XML writers go one after the
  // other: the image and the hit points share five arrays, whose ranges both writers compute and
  // cache on the array. The PNG writer reads the colours alone, which the hit points do not share.
  // The temporaries are made first, in order.
  vtkImageData* image = source->GetImageOutput();
  tools::TemporaryFile* pngFile = nullptr;
  std::vector<std::function<void()>> xml;
  if (formats.png)
  {
    names.png = base + ".png";
    pngFile = &files.add(names.png);
  }
  if (formats.vti)
  {
    names.vti = base + ".vti";
    tools::TemporaryFile& file = files.add(names.vti);
    xml.push_back([image, &file] { tools::writeVti(image, file); });
  }
  if (hits)
  {
    names.hits = base + "-hits.vtp";
    tools::TemporaryFile& file = files.add(names.hits);
    vtkPolyData* data = source->GetHitsOutput();
    xml.push_back([data, &file] { tools::writeVtp(data, file); });
  }
  if (polylines)
  {
    names.rays = base + "-rays.vtp";
    tools::TemporaryFile& file = files.add(names.rays);
    vtkPolyData* data = source->GetPolylinesOutput();
    xml.push_back([data, &file] { tools::writeVtp(data, file); });
  }
  std::vector<std::function<void()>> writes;
  if (pngFile)
    writes.push_back([image, pngFile] { tools::writePng(image, *pngFile); });
  if (!xml.empty())
    writes.push_back(
      [&xml]
      {
        for (const std::function<void()>& write : xml)
          write();
      });
  tools::writeSideBySide(writes);
  stopIfInterrupted();
  return names;
}

/// Whether a frame's hit points may be written: asked for, or by default at frames of at most
/// kHitsByDefaultPixels. Frames whose hit points are neither written nor stored are traced
/// without them (vtkGeodesicSource::GenerateHitPoints), saving their memory.
bool hitPointsWritten(vtkGeodesicSource* source, const Formats& formats)
{
  if (formats.vtp)
    return true;
  if (!formats.vtpIfSmall)
    return false;
  // The frame's size where -r gives it; the scene's own (not read until the trace) keeps them.
  const int* resolution = source->GetResolution();
  if (resolution[0] <= 0 || resolution[1] <= 0)
    return true;
  return static_cast<long long>(resolution[0]) * resolution[1] <= kHitsByDefaultPixels;
}

/// The .pvd files of a series, as one set.
void writeCollections(const std::vector<std::pair<const tools::PvdCollection*, std::string>>& all)
{
  tools::AtomicFileSet files;
  for (const auto& [collection, path] : all)
    if (collection->size() > 0)
      collection->write(files.add(path));
  stopIfInterrupted();
  files.commit();
  for (const auto& [collection, path] : all)
    if (collection->size() > 0)
      std::printf("  wrote %s (ParaView time series of %zu frames)\n", path.c_str(),
                  collection->size());
}

/// --mpi-split: the row layout and the rows per interleaved block.
std::pair<int, int> parseSplit(const std::string& split)
{
  if (split == "contiguous")
    return { vtkGeodesicDistributedSource::CONTIGUOUS, 1 };
  if (split == "interleaved")
    return { vtkGeodesicDistributedSource::INTERLEAVED, 1 };
  if (split.rfind("interleaved:", 0) == 0)
    return { vtkGeodesicDistributedSource::INTERLEAVED,
             parsePositiveInteger("--mpi-split", split.substr(12)) };
  throw UsageError("--mpi-split: expected interleaved, interleaved:K or contiguous, got " +
                   quotedArgument(split));
}

/// Traces a frame on every process. The source agrees on any failure across the processes, so
/// whatever it throws every process throws together.
void traceSharedFrame(vtkGeodesicDistributedSource* source, const std::string& label, bool quiet)
{
  try
  {
    traceFrame(source, label, quiet);
  }
  catch (const InputError& e)
  {
    markSharedFailure();
    if (source->GetInterrupted())
      throw Interrupted();
    if (source->GetStoreFailed())
      throw DatabaseError(withCommandLineAdvice(e.what()));
    throw;
  }
  catch (...)
  {
    markSharedFailure();
    throw;
  }
}

/// The work of every process, from process 0: how even the split was.
void printRankWork(vtkGeodesicDistributedSource* source, const std::string& split)
{
  vtkDoubleArray* work = source->GetRankWork();
  const vtkIdType n = work->GetNumberOfTuples();
  double maxSteps = 0, sumSteps = 0, maxTrace = 0, minTrace = 1e300, maxStore = 0;
  for (vtkIdType p = 0; p < n; ++p)
  {
    maxSteps = std::max(maxSteps, work->GetComponent(p, 0));
    sumSteps += work->GetComponent(p, 0);
    maxTrace = std::max(maxTrace, work->GetComponent(p, 2));
    minTrace = std::min(minTrace, work->GetComponent(p, 2));
    maxStore = std::max(maxStore, work->GetComponent(p, 3));
  }
  std::printf("  %lld processes, %s rows: steps max/mean %.3f, tracing %.2f to %.2f s",
              n > 0 ? static_cast<long long>(n) : 0LL, split.c_str(),
              sumSteps > 0 ? maxSteps * n / sumSteps : 1.0, minTrace, maxTrace);
  if (source->GetStoreFrame())
    std::printf(", storing up to %.2f s", maxStore);
  std::printf("\n");
  for (vtkIdType p = 0; p < n; ++p)
    std::printf("    process %lld: %.0f steps, %.0f rays, %.2f s tracing, %.2f s storing\n",
                static_cast<long long>(p), work->GetComponent(p, 0), work->GetComponent(p, 1),
                work->GetComponent(p, 2), work->GetComponent(p, 3));
}

/// Where and how every frame of a run is written, and the series so far.
struct FrameOutput
{
  Formats formats;
  bool polylines = false;
  bool store = false;
  std::string conninfo, label;
  bool replace = false;
  vtkGeodesicDistributedSource* distributed = nullptr;
  std::string split;
  tools::PvdCollection images, hitSeries, raySeries;
  bool toldOfHits = false; ///< said once that the hit points were left out by default
};

/// The write phase of traced frame k. Its files and its stored copy appear together: the files
/// are written to temporaries, then the frame is stored (an interrupt or an error until its commit
/// leaves nothing), then the files are renamed into place. Past the commit the frame is finished
/// and reported, and an interrupt then stops the run after it.
void finishFrame(vtkGeodesicSource* source, FrameOutput& output, std::size_t k,
                 const std::string& base, const std::string& title)
{
  vtkPolyData* hits = source->GetHitsOutput();
  tools::AtomicFileSet files;
  const FrameFiles written = writeFrameFiles(source, output.formats, output.polylines, base, files);
  vtkIdType id = -1;
  if (output.store)
    id = output.distributed ? output.distributed->GetFrameId()
                            : storeFrame(hits, output.conninfo, output.label, output.replace);
  files.commit();
  const double time = static_cast<double>(k);
  if (!written.vti.empty())
    output.images.add(time, written.vti);
  if (!written.hits.empty())
    output.hitSeries.add(time, written.hits);
  if (!written.rays.empty())
    output.raySeries.add(time, written.rays);
  std::printf("%s: %gx%g, M = %g, a = %g, %s\n", title.c_str(), fieldValue(hits, "Resolution", 0),
              fieldValue(hits, "Resolution", 1), fieldValue(hits, "Mass"), fieldValue(hits, "Spin"),
              fieldString(hits, "IntegrationMethod").c_str());
  for (const std::string& file : files.paths())
    std::printf("  wrote %s\n", file.c_str());
  if (output.formats.vtpIfSmall && written.hits.empty() && !output.toldOfHits)
  {
    std::printf("  hit points not written: the frame has more than %lld pixels (--formats "
                "png,vti,vtp writes them)\n",
                kHitsByDefaultPixels);
    output.toldOfHits = true;
  }
  if (output.distributed)
    printRankWork(output.distributed, output.split);
  if (output.store)
    std::printf("  stored as frame %lld%s\n", static_cast<long long>(id),
                output.distributed ? " (one tile per block of rows)" : "");
  std::fflush(stdout);
  stopIfInterrupted();
}
}

int runTrace(const std::vector<std::string>& args)
{
  const Options options(std::vector<OptionSpec>{ { "output", OptionSpec::Value, 'o' },
                                                 { "formats", OptionSpec::Value },
                                                 { "polylines", OptionSpec::OptionalValue },
                                                 { "quiet", OptionSpec::Flag, 'q' },
                                                 { "sweep", OptionSpec::Value },
                                                 { "orbit", OptionSpec::Value },
                                                 { "store", OptionSpec::OptionalValue },
                                                 { "replace", OptionSpec::Flag },
                                                 { "mpi", OptionSpec::Flag },
                                                 { "mpi-split", OptionSpec::Value } } +
                          sceneOverrideSpecs() + databaseSpecs(),
                        args);
  if (options.help())
  {
    std::printf("%s\n%s\n%s%s\n%s", kHelp, kDatabaseHelp, kSceneOverrideHelp, kExamples,
                kExitCodeHelp);
    return kOk;
  }
  options.expectPositional(1, 1, "the scene file (asrt trace SCENE.json)");
  const std::string scenePath = options.positional()[0];
  const bool mpi = options.has("mpi");
  if (mpi && options.has("polylines"))
    throw UsageError("--polylines cannot be combined with --mpi");
  if (options.has("mpi-split") && !mpi)
    throw UsageError("--mpi-split only makes sense with --mpi");
  Formats formats = parseFormats(options.get("formats", "png,vti"));
  formats.vtpIfSmall = !mpi && !options.has("formats");
  if (mpi && formats.vtp)
    throw UsageError("--mpi writes png and vti; the hits of a distributed frame are read back "
                     "from the store (--store, then asrt show ID --vtp)");
  const bool polylines = options.has("polylines");
  const int stride = options.get("polylines").empty()
                       ? 10
                       : parsePositiveInteger("--polylines", options.get("polylines"));
  const bool quiet = options.has("quiet");
  if (options.has("sweep") && options.has("orbit"))
    throw UsageError("--sweep and --orbit cannot be combined");
  if (options.has("replace") && !options.has("store"))
    throw UsageError("--replace only makes sense with --store");

  // Under --mpi every process runs this; process 0 writes the files and speaks. The command line
  // is checked before MPI starts, so that every process refuses it alike.
  const std::pair<int, int> split = parseSplit(options.get("mpi-split", "interleaved"));
  vtkSmartPointer<vtkGeodesicSource> source;
  vtkSmartPointer<vtkGeodesicDistributedSource> distributed;
  if (mpi)
  {
    distributed = vtkSmartPointer<vtkGeodesicDistributedSource>::New();
    distributed->SetRowLayout(split.first);
    distributed->SetRowsPerBlock(split.second);
    source = distributed;
  }
  else
    source = vtkSmartPointer<vtkGeodesicSource>::New();
  applySceneOverrides(options, source);
  source->SetGeneratePolylines(polylines);
  source->SetPolylineStride(stride);

  // The scene file is read once the command line is known to be good (the orbit's needs the
  // camera from it).
  auto sceneText = [&]
  {
    if (!source->GetSceneText())
      setSceneFile(source, scenePath);
    return std::string(source->GetSceneText());
  };
  std::vector<FrameSetting> frames;
  if (options.has("sweep"))
    frames = sweepFrames(options.get("sweep"));
  else if (options.has("orbit"))
    frames = orbitFrames(options.get("orbit"), sceneText, options);
  sceneText();
  const bool series = !frames.empty();
  if (!series)
    frames.push_back({ std::string(), [](vtkGeodesicSource*) {} });

  const ParallelRun* parallel = mpi ? &startParallelRun() : nullptr;
  const bool speaks = !parallel || parallel->rank == 0;
  if (parallel)
    distributed->SetController(parallel->controller);

  // Connect before tracing: an unreachable database should not cost a trace first (the
  // distributed source does this itself, process 0 resolving the connection for all).
  std::string conninfo;
  std::unique_ptr<RayStore> store; // for the duplicate check before each trace
  if (options.has("store") && distributed)
  {
    distributed->SetStoreFrame(true);
    distributed->SetConnectionString(databaseGiven(options).c_str());
    distributed->SetLabel(options.get("store").c_str());
    distributed->SetReplaceExisting(options.has("replace"));
  }
  else if (options.has("store"))
  {
    conninfo = databaseConnection(options);
    store = std::make_unique<RayStore>(conninfo);
    limitReads(*store);
    store->migrate();
  }

  const double maxShare = maxFailedShare(options);
  const std::string prefix = outputPrefix(options, scenePath);
  const std::string name = vtksys::SystemTools::GetFilenameWithoutLastExtension(scenePath);
  FrameOutput output;
  output.formats = formats;
  output.polylines = polylines;
  output.store = options.has("store");
  output.conninfo = conninfo;
  output.label = options.get("store");
  output.replace = options.has("replace");
  output.distributed = distributed;
  output.split = options.get("mpi-split", "interleaved");
  // Every frame of a series is checked before the first is traced: one that would be refused
  // (a camera sent to infinity by --orbit 3:1e308, a spin swept past the mass) must not leave the
  // frames before it behind.
  if (series)
    for (const FrameSetting& frame : frames)
    {
      frame.apply(source);
      tools::VtkMessageCatcher messages;
      messages.watch(source);
      source->GetFrameSceneText();
      if (messages.failed())
        throw InputError(frame.describe + ": " + messages.firstError());
    }
  for (std::size_t k = 0; k < frames.size(); ++k)
  {
    frames[k].apply(source);
    char number[32];
    std::snprintf(number, sizeof number, "-%03zu", k);
    const std::string base = series ? prefix + number : prefix;
    const std::string label =
      series ? name + " [" + std::to_string(k + 1) + "/" + std::to_string(frames.size()) + "]"
             : name;
    if (distributed)
      traceSharedFrame(distributed, "trace " + label, quiet || !speaks);
    else
    {
      if (store)
        refuseStoredFrame(*store, source, options.has("replace"));
      source->SetGenerateHitPoints(output.store || hitPointsWritten(source, formats));
      traceFrame(source, "trace " + label, quiet);
    }
    if (!speaks)
      continue;
    checkRayEnds(source->GetImageOutput(), maxShare, label);

    finishFrame(source, output, k, base, name + (series ? " " : "") + frames[k].describe);
  }
  if (series && speaks)
    writeCollections({ { &output.images, prefix + ".pvd" },
                       { &output.hitSeries, prefix + "-hits.pvd" },
                       { &output.raySeries, prefix + "-rays.pvd" } });
  return kOk;
}
}
}
