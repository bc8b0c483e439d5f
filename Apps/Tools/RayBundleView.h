// A 3D view of traced rays around the hole: the rays of vtkGeodesicSource's port 2 as polylines
// coloured by how they ended (or by |H|, r, λ along them), the scene's objects and the horizon
// from vtkGeodesicSceneGeometry, the eye as a dot, seen from the side of the line of sight.
// Rendered to a PNG off screen or shown in a window. Debian's VTK renders through GLX only, so
// both need an X display (run under `xvfb-run -a` on a machine without one).
#ifndef asrt_tools_RayBundleView_h
#define asrt_tools_RayBundleView_h

#include "vtkSmartPointer.h"

#include <string>
#include <utility>
#include <vector>

class vtkGeodesicSource;
class vtkIntArray;
class vtkRenderer;

namespace asrt
{
namespace tools
{
class TemporaryFile;

enum class RayColoring
{
  Termination, ///< escaped, captured, hit, ... (categorical)
  AbsH,        ///< |H| along the ray, log scale: the integrator's constraint error
  Radius,      ///< Boyer–Lindquist-like r along the ray
  Lambda       ///< affine parameter from the eye
};
/// "termination", "absh", "r", "lambda" (any case); throws std::invalid_argument otherwise.
RayColoring rayColoringFromName(const std::string& name);

/// The pixels of the middle row and the middle column, every `step` pixels: two fans of rays
/// through the hole (what the figures of ray bundles usually show).
vtkSmartPointer<vtkIntArray> crossPixels(int width, int height, int step);

struct RayBundleStyle
{
  RayColoring coloring = RayColoring::Termination;
  bool showObjects = true;
  double objectOpacity = 0.45;
  std::string title; ///< drawn at the top left; empty for none
};

/// A renderer holding the view. `source` must have been updated with GeneratePolylines on; its
/// scene (file or text, mass and spin overrides) is drawn as well. Throws std::runtime_error if
/// the source has no polylines.
vtkSmartPointer<vtkRenderer> makeRayBundleRenderer(vtkGeodesicSource* source,
                                                   const RayBundleStyle& style);

/// Whether an X display is there to render into: $DISPLAY is set and Xlib can open it.
bool haveDisplay();
/// Renders off screen into a `width` × `height` PNG. Throws std::runtime_error without a display
/// or if the file cannot be written.
void renderToPng(vtkRenderer* renderer, int width, int height, const std::string& path);
/// The same into a member of an AtomicFileSet (in place when the set is committed).
void renderToPng(vtkRenderer* renderer, int width, int height, TemporaryFile& file);
/// Opens a window (mouse: rotate, zoom, pan) until the user closes it. Throws std::runtime_error
/// without a display.
void showInteractive(vtkRenderer* renderer, int width, int height, const std::string& windowName);
}
}

#endif
