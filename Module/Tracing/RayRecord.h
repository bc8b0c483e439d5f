// The records of traced rays: what a frame keeps of each pixel's ray (RayRecord), what the
// Jacobians of its neighbours read of it, and the polylines of traced paths. Plain data: the
// store, the matching and the distribution of frames over ranks need these, not the tracer.
#ifndef asrt_RayRecord_h
#define asrt_RayRecord_h

#include "AsrtTypes.h"
#include "Scene.h"

#include <cmath>
#include <cstdint>
#include <vector>

namespace asrt
{
/// Everything the accumulation stores about one pixel's ray.
struct RayRecord
{
  std::int32_t i = 0, j = 0;     ///< pixel (column from the left, row from the bottom)
  Vec3 origin = Vec3::Zero();    ///< the eye
  Vec3 direction = Vec3::Zero(); ///< unit direction in the observer's frame (right, up, forward)
  Vec4 momentum = Vec4::Zero();  ///< initial covariant momentum p_μ
  Termination termination = Termination::Running;
  std::int32_t objectId = -1;   ///< hit object, −1 if none
  Vec3 hitPoint = Vec3::Zero(); ///< refined hit, or where the ray ended
  Vec3 hitNormal = Vec3::Zero();
  double u = 0, v = 0;         ///< surface coordinates of the hit
  double chordError = 0;       ///< |chord hit − refined hit|: what refinement corrected
  double affineLength = 0;     ///< λ from the eye to the hit (or the end)
  double winding = 0;          ///< angle swept around the hole (radians)
  std::int32_t imageOrder = 0; ///< half-turns: floor(winding / π)
  std::int64_t steps = 0;
  double maxAbsH = 0;
  Color color =
    Color::Zero(); ///< the pixel's colour: filtered and sampled as the frame's rendering says
  /// How many rays the colour comes from: 1 for the centre ray alone, more for a supersampled
  /// pixel (the centre ray's fields are still the record's).
  std::int32_t raysPerPixel = 1;
  /// Whether the centre ray was traced; false for a record interpolated by the adaptive grid
  /// (AdaptiveGrid.h), whose raysPerPixel counts only the rays anti-aliasing traced for it.
  bool traced = true;
  /// Screen-space Jacobian ∂(u, v)/∂(i, j) of the hit from neighbouring pixels that hit the same
  /// object in the same image order (u differences taken modulo 1); NaN where no neighbour does.
  double dudi = 0, dudj = 0, dvdi = 0, dvdj = 0;
};

/// u(a) − u(b) the short way round, in [−½, ½]: u is periodic on closed surfaces (the sky, spheres,
/// cylinders, disks), so neighbouring rays across the seam differ by a little, not by almost 1.
inline double shortUDifference(double a, double b)
{
  return (a - b) - std::round(a - b);
}

/// What the Jacobians of a pixel's neighbours read of its record.
struct JacobianSample
{
  std::int32_t i = 0, j = 0;
  double u = 0, v = 0;
  std::int32_t objectId = -1;
  std::int32_t imageOrder = 0;
  Termination termination = Termination::Running;
};

/// The part of a record its neighbours' Jacobians read.
inline JacobianSample jacobianSample(const RayRecord& r)
{
  return { r.i, r.j, r.u, r.v, r.objectId, r.imageOrder, r.termination };
}

/// Whether two rays end alike: on the same object in the same image order, or the same way. An
/// edge runs between two pixels whose centre rays do not: the adaptive grid refines there, the
/// anti-aliasing samples there.
inline bool endsAlike(const JacobianSample& a, const JacobianSample& b)
{
  return a.objectId == b.objectId && a.imageOrder == b.imageOrder && a.termination == b.termination;
}
inline bool endsAlike(const RayRecord& a, const RayRecord& b)
{
  return a.objectId == b.objectId && a.imageOrder == b.imageOrder && a.termination == b.termination;
}

/// One point of a traced ray's polyline.
struct PathPoint
{
  Vec3 x;
  double lambda;
  double r;
  double absH;
};

/// The traced path of one pixel's ray: the points from the eye on (vtkGeodesicSource's
/// polylines, stored with a frame by RayStore).
struct RayPath
{
  std::int32_t i = 0, j = 0; ///< the pixel
  Termination termination = Termination::Running;
  std::vector<PathPoint> points;
};
}

#endif
