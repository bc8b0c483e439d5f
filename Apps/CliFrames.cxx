// asrt list, asrt show: the frames accumulated in PostgreSQL.
#include "Cli.h"

#include "DataFiles.h"
#include "Progress.h"
#include "RayStore.h"
#include "StoreConnection.h"
#include "VtkMessages.h"
#include "vtkGeodesicPostgreSQLReader.h"

#include "vtkImageData.h"
#include "vtkNew.h"
#include "vtkPolyData.h"

#include <cmath>
#include <cstdio>

namespace asrt
{
namespace cli
{
namespace
{
const char* const kListHelp = R"(Usage: asrt list [options]

Lists the frames stored in PostgreSQL (by "asrt trace --store" or vtkGeodesicPostgreSQLWriter):
id, scene name, label, mass M, spin a, camera position, size, integrator, number of rays, the
seconds spent tracing (when the writer said) and writing, and when it was stored. Names and
labels are shown with control characters escaped.
)";

const char* const kShowHelp = R"(Usage: asrt show ID [options]

Prints everything stored about frame ID (see "asrt list"): its scene and parameters, the
integrator, rays, times. With any of the options below it also reads the frame back from the
database through vtkGeodesicPostgreSQLReader and writes it:
  --png FILE       the picture, shaded again from the stored rays
  --vti FILE       the frame as VTK image data
  --vtp FILE       the hit points with every ray's record
  --where SQL      read only the rays matching a condition over the columns of the view
                   rays_v, e.g. "object_id = 2 AND image_order = 1" (the other pixels stay
                   black). It may use the columns, numbers, 'strings', TRUE, FALSE, NULL,
                   + - * / % ^, = <> != < <= > >=, AND, OR, NOT, parentheses, IS [NOT]
                   NULL, [NOT] BETWEEN, [NOT] IN (a list of constants) and the functions
                   abs, sign, sqrt, cbrt, exp, ln, log, log10, power, mod, floor, ceil,
                   ceiling, round, trunc, pi, degrees, radians, sin, cos, tan, asin, acos,
                   atan, atan2, sinh, cosh, tanh, greatest, least; anything else (other
                   names, SELECT, casts, comments, ';') is refused before it reaches the
                   server. It runs in a read-only transaction, as the role asrt_predicate,
                   which may read the rays and nothing else
  --scene          print the frame's scene as JSON (what re-traces it exactly)
)";

const char* const kFrameExamples = R"(
Examples:
  asrt list
  asrt show 3
  asrt show 3 --png frame3.png --vtp frame3-hits.vtp
  asrt show 3 --where "image_order >= 1" --png rings.png
)";

std::string seconds(double s)
{
  if (std::isnan(s))
    return "-";
  char text[32];
  std::snprintf(text, sizeof text, "%.2f", s);
  return text;
}

std::string vec(const Vec3& v)
{
  char text[96];
  std::snprintf(text, sizeof text, "%g,%g,%g", v.x(), v.y(), v.z());
  return text;
}

std::string clipped(const std::string& text, std::size_t width)
{
  const std::string p = printable(text);
  if (p.size() <= width)
    return p;
  // Cut at a character boundary: never inside a UTF-8 sequence.
  std::size_t cut = width - 3;
  while (cut > 0 && (static_cast<unsigned char>(p[cut]) & 0xC0) == 0x80)
    --cut;
  return p.substr(0, cut) + "...";
}

/// Opens the store and upgrades an older schema; list and show only read, so they create none,
/// except in the private server's own database. Every failure is a database error, but for one
/// that Ctrl-C brought about (a read it cancelled): that is the interrupt.
template<class F>
auto withStore(const Options& options, const std::string& conninfo, F&& f)
{
  try
  {
    RayStore store(conninfo);
    limitReads(store);
    if (storeConnectionIsPrivate(databaseGiven(options).c_str()))
      store.migrate();
    else
      store.upgrade();
    return f(store);
  }
  catch (const StoreError& e)
  {
    if (tools::interruptRequested())
      throw Interrupted();
    throw DatabaseError(e.what());
  }
}
}

int runList(const std::vector<std::string>& args)
{
  const Options options(databaseSpecs(), args);
  if (options.help())
  {
    std::printf("%s\n%s%s\n%s", kListHelp, kDatabaseHelp, kFrameExamples, kExitCodeHelp);
    return kOk;
  }
  options.expectPositional(0, 0, "");
  const std::vector<FrameInfo> frames = withStore(
    options, databaseConnection(options), [](RayStore& store) { return store.listFrames(); });
  if (frames.empty())
  {
    std::printf("no frames stored yet (asrt trace SCENE --store stores one)\n");
    return kOk;
  }
  std::printf("%5s  %-20s %-16s %7s %6s  %-16s %9s  %-16s %8s %7s %7s  %s\n", "id", "name", "label",
              "M", "a", "camera", "size", "method", "rays", "trace_s", "write_s", "stored (UTC)");
  for (const FrameInfo& f : frames)
  {
    const std::string size = std::to_string(f.key.width) + "x" + std::to_string(f.key.height);
    std::printf("%5lld  %-20s %-16s %7g %6g  %-16s %9s  %-16s %8lld %7s %7s  %s\n",
                static_cast<long long>(f.id), clipped(f.name, 20).c_str(),
                clipped(f.label, 16).c_str(), f.key.spacetime.mass, f.key.spacetime.spin,
                clipped(vec(f.key.cameraPosition), 16).c_str(), size.c_str(),
                clipped(f.key.method, 16).c_str(), static_cast<long long>(f.rayCount),
                seconds(f.traceSeconds).c_str(), seconds(f.writeSeconds).c_str(),
                printable(f.createdAt).c_str());
  }
  return kOk;
}

int runShow(const std::vector<std::string>& args)
{
  const Options options(std::vector<OptionSpec>{ { "png", OptionSpec::Value },
                                                 { "vti", OptionSpec::Value },
                                                 { "vtp", OptionSpec::Value },
                                                 { "where", OptionSpec::Value },
                                                 { "scene", OptionSpec::Flag } } +
                          databaseSpecs(),
                        args);
  if (options.help())
  {
    std::printf("%s\n%s%s\n%s", kShowHelp, kDatabaseHelp, kFrameExamples, kExitCodeHelp);
    return kOk;
  }
  options.expectPositional(1, 1, "the frame id (asrt show ID; asrt list shows the ids)");
  const std::int64_t id = parseFrameId(options.positional()[0]);
  const std::string conninfo = databaseConnection(options);
  auto [info, sceneText] =
    withStore(options, conninfo,
              [id](RayStore& store)
              { return std::make_pair(store.frameInfo(id), store.frameSceneText(id)); });
  const FrameKey& k = info.key;
  std::printf("frame %lld\n", static_cast<long long>(info.id));
  std::printf("  name           %s\n", printable(info.name).c_str());
  std::printf("  label          %s\n", printable(info.label).c_str());
  std::printf("  mass           %.17g\n", k.spacetime.mass);
  std::printf("  spin           %.17g\n", k.spacetime.spin);
  std::printf("  charge         %.17g\n", k.spacetime.charge);
  std::printf("  camera         %s\n", vec(k.cameraPosition).c_str());
  std::printf("  focal point    %s\n", vec(k.focalPoint).c_str());
  std::printf("  view up        %s\n", vec(k.viewUp).c_str());
  std::printf("  view angle     %g deg\n", k.viewAngle);
  std::printf("  size           %d x %d\n", k.width, k.height);
  std::printf("  method         %s\n", printable(k.method).c_str());
  std::printf("  step           %g\n", k.step);
  std::printf("  tolerances     rtol %g, atol %g\n", k.relativeTolerance, k.absoluteTolerance);
  std::printf("  rays           %lld (in %d tile%s)\n", static_cast<long long>(info.rayCount),
              info.tileCount, info.tileCount == 1 ? "" : "s");
  std::printf("  traced in      %s s\n", seconds(info.traceSeconds).c_str());
  std::printf("  written in     %s s\n", seconds(info.writeSeconds).c_str());
  std::printf("  stored         %s\n", printable(info.createdAt).c_str());
  std::printf("  frame hash     %s\n", info.frameHash.c_str());
  if (options.has("scene"))
    std::printf("%s\n", sceneText.c_str());

  if (!options.has("png") && !options.has("vti") && !options.has("vtp"))
    return kOk;
  vtkNew<vtkGeodesicPostgreSQLReader> reader;
  tools::VtkMessageCatcher messages;
  messages.watchAlgorithm(reader);
  reader->SetConnectionString(conninfo.c_str());
  limitReads(reader);
  reader->SetFrameId(static_cast<vtkIdType>(id));
  if (options.has("where"))
    reader->SetPredicate(options.get("where").c_str());
  reader->Update();
  if (tools::interruptRequested())
    throw Interrupted();
  if (messages.failed())
    throw DatabaseError(messages.firstError());
  // The exports appear together, or none of them.
  tools::AtomicFileSet files;
  if (options.has("png"))
    tools::writePng(reader->GetImageOutput(), files.add(options.get("png")));
  if (options.has("vti"))
    tools::writeVti(reader->GetImageOutput(), files.add(options.get("vti")));
  if (options.has("vtp"))
    tools::writeVtp(reader->GetHitsOutput(), files.add(options.get("vtp")));
  if (tools::interruptRequested())
    throw Interrupted();
  files.commit();
  for (const std::string& path : files.paths())
    std::printf("  wrote %s\n", path.c_str());
  return kOk;
}
}
}
