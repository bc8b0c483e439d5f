// Small measurements shared by `asrt bench` and the examples: the deflection of a Schwarzschild
// ray against Darwin's exact formula (an independent truth), and the scene loader with VTK's
// image readers for code that traces with the numeric core directly.
#ifndef asrt_tools_Measurements_h
#define asrt_tools_Measurements_h

#include "RayTracer.h"
#include "SceneFile.h"

namespace asrt
{
namespace tools
{
struct Deflection
{
  double measured = 0; ///< swept angle of the traced ray, extended analytically to infinity, − π
  double exact = 0;    ///< Darwin's exact deflection for the same impact parameter
  TraceResult trace;   ///< how the ray went (steps, termination, |H|)
  double relativeError() const;
};

/// Traces a ray of impact parameter b (in M, above b_c = 3√3 M) past a Schwarzschild hole of
/// mass 1 in its equatorial plane with `cfg`, from R = max(1000, 20 b) M back out to R, and
/// compares the angle it swept with Darwin's exact deflection. Throws InvalidParameter for b at
/// or below the critical impact parameter.
Deflection schwarzschildDeflection(const IntegratorConfig& cfg, double b);

/// Reads scene textures as the filters do (vtkGeodesicSource::LoadImagePixels: libpng for PNG,
/// VTK's readers for other formats).
ImageLoader vtkImageLoader();
}
}

#endif
