// Matching two traced frames of one scene pixel by pixel (the paper's rendering engine, first
// half): for each pixel, the pixel of the other frame whose ray hit the same scene point, where
// exactly that point lies there (sub-pixel), and how the neighbourhood maps (a 2×2 Jacobian).
// Also what may differ between two frames of one movie, and the parameters in between.
//
// Plain C++ on Eigen. The spatial search is handed in (PointIndex): the VTK layer passes VTK's
// point locators, so that no search here is O(n²).
#ifndef asrt_FrameMatching_h
#define asrt_FrameMatching_h

#include "RayRecord.h"
#include "SceneDescription.h"
#include "asrtInterpolationModule.h"

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace asrt
{
/// What interpolation needs of one pixel's ray.
struct PixelSample
{
  Vec3 point = Vec3::Zero(); ///< hit point, or where the ray ended
  double u = 0, v = 0;       ///< surface coordinates of the hit
  /// Screen-space Jacobian ∂(u, v)/∂(i, j) of the record, row-major (∂u/∂i, ∂u/∂j, ∂v/∂i,
  /// ∂v/∂j; NaN where the tracer had no neighbour).
  std::array<double, 4> jacobian{ { 0, 0, 0, 0 } };
  double pathLength = 0;
  std::int32_t objectId = -1;
  std::int32_t imageOrder = 0;
  Termination termination = Termination::Running;
  std::array<std::uint8_t, 3> rgb{ { 0, 0, 0 } }; ///< as the source's image stores it
};

/// The 8-bit colour the source's image gives a ray colour: round(255 · clamp(c, 0, 1)).
ASRTINTERPOLATION_EXPORT std::array<std::uint8_t, 3> imageColor(const Color& c);
ASRTINTERPOLATION_EXPORT PixelSample sampleOf(const RayRecord& r);

/// One whole frame, row-major from the bottom-left: pixel (i, j) is pixels[j · width + i].
struct FrameSamples
{
  int width = 0, height = 0;
  double viewAngle = 30; ///< vertical, degrees (the angular size of a pixel, for tolerances)
  std::vector<PixelSample> pixels;
};

/// Assembles a whole frame from `count` samples produced by `next(k, i, j, sample)`. Throws
/// InvalidParameter, naming `which` frame and the pixel, unless every pixel of the width × height
/// frame comes exactly once and each sample is finite where it must be: path length, and the hit
/// point of rays that hit something or escaped.
ASRTINTERPOLATION_EXPORT FrameSamples assembleFrame(
  int width, int height, double viewAngle, std::size_t count,
  const std::function<void(std::size_t, int&, int&, PixelSample&)>& next, const std::string& which);
ASRTINTERPOLATION_EXPORT FrameSamples samplesFromRecords(const std::vector<RayRecord>& records,
                                                         int width, int height, double viewAngle,
                                                         const std::string& which);

/// What a pixel's ray ended on, for matching: a point on an object, the empty sky (escaped with no
/// celestial sphere), the hole's shadow (captured), or nothing usable (step budget, failure).
enum class SampleKind : std::uint8_t
{
  Surface,
  Escaped,
  Shadow,
  Lost
};
ASRTINTERPOLATION_EXPORT SampleKind kindOf(const PixelSample& s);

enum class MatchKind : std::uint8_t
{
  Matched = 0,   ///< the same scene point (or, for the shadow, the same place in the shadow)
  OneSided = 1,  ///< not seen in the other frame (occluded, out of view, or unusable ray)
  Ambiguous = 2, ///< several images of the point, same order, path lengths tied
};

/// Where a pixel's scene point lies in the other frame.
struct PixelMatch
{
  /// Position in the other frame, in pixel units (pixel (i, j) at (i, j)). Matched pixels: the
  /// refined position of the point; the others: extrapolated from matched neighbours.
  float x = 0, y = 0;
  /// ∂(x, y)/∂(i, j), row-major: how this pixel's neighbourhood maps into the other frame.
  std::array<float, 4> jacobian{ { 1, 0, 0, 1 } };
  std::int32_t partner = -1; ///< the other frame's pixel nearest the point (matched only)
  MatchKind kind = MatchKind::OneSided;
};

struct Correspondence
{
  int width = 0, height = 0;
  std::vector<PixelMatch> aToB; ///< one per pixel of A
  std::vector<PixelMatch> bToA; ///< one per pixel of B
};

/// Nearest-point queries over a fixed set of points; queries must be thread-safe.
class ASRTINTERPOLATION_EXPORT PointIndex
{
public:
  virtual ~PointIndex();
  /// Index of the point nearest x within `radius`, −1 if there is none.
  virtual std::int64_t nearestWithin(const Vec3& x, double radius) const = 0;
  /// Indices of all points within `radius` of x (any order), replacing `out`'s contents.
  virtual void within(const Vec3& x, double radius, std::vector<std::int64_t>& out) const = 0;
};
using PointIndexFactory = std::function<std::unique_ptr<PointIndex>(const std::vector<Vec3>&)>;

struct MatchOptions
{
  /// A point matches a pixel whose hit lies within this many pixel footprints of it (the
  /// footprint: the distance to the nearest neighbouring hit of the same image).
  double tolerance = 1.5;
  /// Candidates whose path lengths differ from the pixel's by amounts closer than this (relative
  /// to its path length) are tied: the pixel is ambiguous.
  double pathLengthTie = 1e-3;
  /// One-sided pixels take the motion of matched pixels of the same image within this radius
  /// (pixels); failing that, of any matched pixel nearby; failing that, a push-pull extrapolation.
  int extrapolationRadius = 8;
};

/// Matches A to B and B to A. The rules, per pixel:
///  - a ray that hit an object (or escaped into an empty sky) matches the rays of the other frame
///    that hit the same object in the same image order (floor(winding/π)) within the tolerance of
///    its hit point; candidates that are neighbouring pixels are one image, distinct clusters are
///    nested images of the same order: the one whose path length is closest wins, a tie is
///    ambiguous. The position is refined to sub-pixel with the partner's (u, v) Jacobian
///    (Δ(i, j) = J⁻¹ Δ(u, v), u the short way round), or with its neighbours' hit points where
///    (u, v) has no Jacobian, stepping to the pixel that map points at while that brings the
///    point closer; a point it still puts more than a pixel away, or beyond the frame's edge, is
///    not seen there (one-sided). The neighbourhood maps by D = J_B⁻¹ J_A;
///  - the shadow (captured rays) is one region in each frame: its pixels map by the similarity
///    that takes A's shadow (centroid, radius √(area/π)) onto B's;
///  - the rest is one-sided, moving as its matched neighbours do.
/// `progress(fraction)` is called now and then from the calling thread.
ASRTINTERPOLATION_EXPORT Correspondence matchFrames(
  const FrameSamples& a, const FrameSamples& b, const PointIndexFactory& index,
  const MatchOptions& options = {}, const std::function<void(double)>& progress = nullptr);

/// The parameters that may change between the two frames of a movie.
struct FrameParameters
{
  SpacetimeParameters spacetime;
  Vec3 position = Vec3::Zero();
  Vec3 focalPoint = Vec3::Zero();
  Vec3 viewUp = Vec3::UnitZ();
};

enum class CameraPath
{
  Automatic, ///< Orbit when either frame has a hole (M > 0), Linear in flat space
  Linear,    ///< the eye moves on the straight line (a dolly)
  Orbit      ///< about the hole (the origin): radius linear, direction along the great circle
};
ASRTINTERPOLATION_EXPORT const char* toString(CameraPath p);

ASRTINTERPOLATION_EXPORT FrameParameters parametersOf(const SceneDescription& d);
ASRTINTERPOLATION_EXPORT void applyParameters(const FrameParameters& p, SceneDescription& d);
/// The parameters at t ∈ [0, 1]: mass, spin and charge linear (so |a| ≤ M holds throughout),
/// focal point linear, view-up normalised-linear, the eye by `path`. Throws InvalidParameter if
/// the path is undefined (an orbit between opposite directions).
ASRTINTERPOLATION_EXPORT FrameParameters interpolateParameters(const FrameParameters& a,
                                                               const FrameParameters& b, double t,
                                                               CameraPath path);
/// Empty if a and b are frames of one scene, differing at most in mass, spin, charge, camera
/// position, focal point, view-up and integration method (which "auto" resolves per spacetime);
/// else the first difference, e.g. "objects[1].radius: 0.5 vs 0.7".
ASRTINTERPOLATION_EXPORT std::string sceneDifference(const SceneDescription& a,
                                                     const SceneDescription& b);
}

#endif
