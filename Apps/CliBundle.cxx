// asrt bundle: a 3D view of traced rays around the hole, to a PNG or a window.
#include "Cli.h"

#include "DataFiles.h"
#include "Progress.h"
#include "RayBundleView.h"
#include "VtkMessages.h"
#include "vtkGeodesicSource.h"

#include "vtkFieldData.h"
#include "vtkInformation.h"
#include "vtkIntArray.h"
#include "vtkNew.h"
#include "vtkPolyData.h"
#include "vtkRenderer.h"
#include "vtkStreamingDemandDrivenPipeline.h"

#include <vtksys/SystemTools.hxx>

#include <cstdio>

namespace asrt
{
namespace cli
{
namespace
{
const char* const kHelp = R"(Usage: asrt bundle SCENE.json [options]

Traces a bundle of rays from the scene's camera and draws them in 3D around the hole: the
horizon (black), the scene's objects (translucent), the eye (white dot) and the rays, coloured
by how they ended (escaped, captured, hit an object, ...) or by a quantity along them. Writes a
PNG, or opens a window you can turn with the mouse (--interactive). Rendering needs an X
display: on a machine without one, run it under xvfb-run -a.

Options:
  -o, --output FILE     the PNG (default: SCENE-bundle.png in the current directory; a
                        directory gets that name)
  --size WxH            picture size (default 800x600, at most 8192x8192)
  --rays cross|grid     which pixels' rays: the middle row and column of the image (cross,
                        default) or every STEP-th pixel of the image in both directions
  --step N              pixels between rays (default 2 for cross, 8 for grid)
  --color-by WHAT       termination (default), absh (|H|, the Hamiltonian constraint error,
                        log scale), r (the radius), lambda (the affine parameter)
  --no-objects          draw the rays and the horizon only
  --vtp FILE            also write the rays as VTK poly data
  --interactive         open a window instead of writing the PNG
  -q, --quiet           no progress on stderr
The rays are traced at the scene's image size unless -r/--resolution says otherwise (41x41
is a good size for a bundle).
)";

const char* const kExamples = R"(
Examples:
  asrt bundle Data/scenes/fig1-cylinders.json -r 41x41 -o out/
  asrt bundle Data/scenes/kerr-disk.json -r 41x41 --color-by r --interactive
  xvfb-run -a asrt bundle Data/scenes/fig1-cylinders.json --rays grid --step 10 --color-by absh
)";
}

int runBundle(const std::vector<std::string>& args)
{
  const Options options(std::vector<OptionSpec>{ { "output", OptionSpec::Value, 'o' },
                                                 { "size", OptionSpec::Value },
                                                 { "rays", OptionSpec::Value },
                                                 { "step", OptionSpec::Value },
                                                 { "color-by", OptionSpec::Value },
                                                 { "no-objects", OptionSpec::Flag },
                                                 { "vtp", OptionSpec::Value },
                                                 { "interactive", OptionSpec::Flag },
                                                 { "quiet", OptionSpec::Flag, 'q' } } +
                          sceneOverrideSpecs(),
                        args);
  if (options.help())
  {
    std::printf("%s\n%s%s\n%s", kHelp, kSceneOverrideHelp, kExamples, kExitCodeHelp);
    return kOk;
  }
  options.expectPositional(1, 1, "the scene file (asrt bundle SCENE.json)");
  const std::string scenePath = options.positional()[0];
  const auto size = options.size("size").value_or(std::make_pair(800, 600));
  // A window or offscreen buffer beyond this fails in X or OpenGL, not with a message.
  constexpr int kMaxPictureSide = 8192;
  if (size.first > kMaxPictureSide || size.second > kMaxPictureSide)
    throw UsageError("--size: at most " + std::to_string(kMaxPictureSide) + " pixels a side, got " +
                     options.get("size"));
  const std::string rays = options.get("rays", "cross");
  if (rays != "cross" && rays != "grid")
    throw UsageError("--rays: 'cross' or 'grid', got " + quotedArgument(rays));
  const int step = options.positiveInteger("step").value_or(rays == "cross" ? 2 : 8);
  tools::RayBundleStyle style;
  try
  {
    style.coloring = tools::rayColoringFromName(options.get("color-by", "termination"));
  }
  catch (const std::invalid_argument& e)
  {
    throw UsageError(std::string("--color-by: ") + e.what());
  }
  style.showObjects = !options.has("no-objects");
  const bool interactive = options.has("interactive");
  // Before tracing: a missing display should not cost a trace first.
  if (!tools::haveDisplay())
    throw std::runtime_error("no X display to render into (DISPLAY is unset or unreachable); "
                             "VTK here renders through GLX only: run the command under "
                             "xvfb-run -a");
  const std::string output =
    interactive ? std::string() : outputPath(options, scenePath, "-bundle.png");

  vtkNew<vtkGeodesicSource> source;
  applySceneOverrides(options, source);
  setSceneFile(source, scenePath);
  source->GeneratePolylinesOn();
  // The image size decides the rays' directions: learn it (the scene's, or the override).
  {
    tools::VtkMessageCatcher messages;
    messages.watchAlgorithm(source);
    source->UpdateInformation();
    if (messages.failed())
      throw InputError(messages.firstError());
  }
  int extent[6];
  source->GetOutputInformation(0)->Get(vtkStreamingDemandDrivenPipeline::WHOLE_EXTENT(), extent);
  if (rays == "cross")
  {
    vtkSmartPointer<vtkIntArray> pixels = tools::crossPixels(extent[1] + 1, extent[3] + 1, step);
    source->SetPolylinePixels(pixels);
    source->SetPixelSubset(pixels); // only these rays are needed
  }
  else
    source->SetPolylineStride(step);
  const std::string name = vtksys::SystemTools::GetFilenameWithoutLastExtension(scenePath);
  traceFrame(source, "bundle " + name, options.has("quiet"));
  checkRayEnds(source->GetImageOutput(), maxFailedShare(options), name);
  const vtkIdType count = source->GetPolylinesOutput()->GetNumberOfCells();

  // The rays' file and the picture appear together.
  tools::AtomicFileSet files;
  if (options.has("vtp"))
    tools::writeVtp(source->GetPolylinesOutput(), files.add(options.get("vtp")));
  char title[256];
  std::snprintf(title, sizeof title, "%s: %lld rays", name.c_str(), static_cast<long long>(count));
  style.title = title;
  vtkSmartPointer<vtkRenderer> renderer = tools::makeRayBundleRenderer(source, style);
  if (interactive)
  {
    files.commit();
    if (options.has("vtp"))
      std::printf("wrote %s\n", options.get("vtp").c_str());
    tools::showInteractive(renderer, size.first, size.second, "asrt bundle " + name);
    return kOk;
  }
  tools::renderToPng(renderer, size.first, size.second, files.add(output));
  if (tools::interruptRequested())
    throw Interrupted();
  files.commit();
  if (options.has("vtp"))
    std::printf("wrote %s\n", options.get("vtp").c_str());
  std::printf("%s: %lld rays -> %s\n", name.c_str(), static_cast<long long>(count), output.c_str());
  return kOk;
}
}
}
