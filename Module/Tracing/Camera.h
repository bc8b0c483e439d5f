// The camera and its observer: where the eye is, which way it looks, how it moves, and the photon
// momentum of each pixel's ray, built in the observer's local orthonormal frame.
#ifndef asrt_Camera_h
#define asrt_Camera_h

#include "Spacetime.h"
#include "asrtTracingModule.h"

#include <string>

namespace asrt
{
/// How the observer moves. Its 4-velocity u defines the frame in which the pixel directions are
/// set.
enum class ObserverMotion
{
  Static, ///< u ∝ ∂_t; exists only where g_tt < 0 (outside any ergosphere)
  ZAMO    ///< zero angular momentum (u_φ = 0): exists everywhere outside the horizon
};

ASRTTRACING_EXPORT const char* toString(ObserverMotion m);
/// "static" or "zamo"; throws InvalidParameter naming the accepted values otherwise.
ASRTTRACING_EXPORT ObserverMotion observerMotionFromString(const std::string& s);

/// A pinhole camera with the parameters vtkCamera users know. Positions are in the spacetime's
/// Cartesian (Kerr–Schild) chart, in units of M; the view angle is the vertical one, in degrees.
struct CameraParameters
{
  Vec3 position = Vec3(0, -30, 0);
  Vec3 focalPoint = Vec3(0, 0, 0);
  Vec3 viewUp = Vec3(0, 0, 1);
  double viewAngle = 30.0;
  int width = 200;
  int height = 200;
  ObserverMotion observer = ObserverMotion::Static;
};

/// The camera on a spacetime: checks its parameters, builds the observer's orthonormal tetrad once,
/// and hands out each pixel's initial phase-space point.
class ASRTTRACING_EXPORT Camera
{
public:
  /// Throws InvalidParameter for non-finite or degenerate parameters (zero resolution, view angle
  /// outside (0, 180), view-up parallel to the view direction, focal point at the position), a
  /// position inside the horizon (r ≤ r₊), or a static observer inside an ergosphere (g_tt ≥ 0).
  Camera(const Spacetime& st, const CameraParameters& params);

  const CameraParameters& parameters() const { return this->Params; }
  /// Unit spatial direction of pixel (i, j) in the observer's frame, as components along the
  /// tetrad's right, up and forward legs. i runs along the width (left to right), j along the
  /// height (bottom to top), pixel centres at (i + ½, j + ½).
  Vec3 localDirection(double i, double j) const;
  /// The initial state of the ray that reaches the eye through pixel (i, j): the null geodesic
  /// leaving the eye in the pixel's direction, past-directed (traced backwards in time), with
  /// |E_local| = 1 and H = 0 to round-off.
  PhasePoint pixelRay(double i, double j) const;
  /// The observer's 4-velocity u^μ and tetrad legs e_right, e_up, e_forward (contravariant).
  const Vec4& velocity() const { return this->U; }
  const Vec4& right() const { return this->Right; }
  const Vec4& up() const { return this->Up; }
  const Vec4& forward() const { return this->Forward; }
  /// Half-angle tangent of the vertical field of view.
  double tanHalfAngle() const { return this->TanHalf; }

private:
  const Spacetime& St;
  CameraParameters Params;
  Mat4 G; // g_μν at the eye
  Vec4 X; // the eye's coordinates
  Vec4 U, Right, Up, Forward;
  double TanHalf;
};
}

#endif
