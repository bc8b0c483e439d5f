// What one frame is traced from: the spacetime, the camera, the scene's objects, the integrator
// and the tracing tolerances, and which pixels (all, or a subset). Reading and writing it as JSON
// is SceneFile.h's.
#ifndef asrt_SceneDescription_h
#define asrt_SceneDescription_h

#include "Antialiasing.h"
#include "Camera.h"
#include "RayRecord.h"
#include "RayTracer.h"
#include "Scene.h"
#include "SpacetimeParameters.h"
#include "asrtTracingModule.h"

#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace asrt
{
/// Identifies a frame that holds only some of its pixels, traced on their own (e.g. the rays an
/// interpolator re-traces): how many and a digest of which. It is part of the frame's identity, so
/// that such a frame never collides with the whole frame at the same parameters. Whole frames have
/// count 0 and their scene text carries no "subset" field (their identity is unchanged).
struct PixelSubsetId
{
  std::int64_t count = 0;
  std::string digest; ///< 16 hex digits: FNV-1a 64 of the sorted, distinct (i, j) as int32 pairs
  /// Empty where the pixels' edge neighbours were traced; else 16 hex digits, borderDigest of the
  /// neighbour samples their records read instead (FrameTracer::tracePixelsBeside), on which
  /// their Jacobians and colours then depend.
  std::string border;
  bool operator==(const PixelSubsetId& o) const
  {
    return this->count == o.count && this->digest == o.digest && this->border == o.border;
  }
};

/// The identity of a set of pixels: sorted and deduplicated first, so the order and repetitions
/// of the list do not matter. An empty list gives count 0 (a whole frame).
ASRTTRACING_EXPORT PixelSubsetId pixelSubsetId(std::vector<std::pair<int, int>> pixels);

/// The identity of neighbour samples given in place of traced neighbours (PixelSubsetId::border):
/// 16 hex digits, FNV-1a 64 over each sample's fields (i, j, objectId, imageOrder and termination
/// as int32, u and v as the bits of their doubles), the samples in pixel order; empty for none.
ASRTTRACING_EXPORT std::string borderDigest(std::vector<JacobianSample> border);

struct SceneDescription
{
  std::string name;
  /// The hole: the scene file's "spacetime" (mass required there).
  SpacetimeParameters spacetime{ 1.0, 0.0, 0.0 };
  CameraParameters camera;
  IntegratorConfig integrator;
  TraceOptions tracing;
  /// The "rendering" section: how pixels are anti-aliased (Antialiasing.h).
  AntialiasOptions rendering;
  std::shared_ptr<Scene> scene = std::make_shared<Scene>();
  /// Non-empty for a frame of only some pixels (the optional root field "subset": {"pixels": n,
  /// "digest": "..."}, written by the tools, not by hand).
  PixelSubsetId subset;
  /// The JSON it was parsed from, normalised: nlohmann's dump() of the parsed document (keys
  /// sorted, no whitespace), so equal documents give equal text (for storage and hashing).
  std::string sourceText;
};

/// The most pixels a frame may have: at ~200 bytes a ray record, 2²⁸ pixels is already ~50 GB.
constexpr long long kMaxFramePixels = 1LL << 28;

/// The largest magnitude of a length in a scene (the mass, a coordinate of the camera or of its
/// focal point, the escape radius, a celestial sphere's radius) and the smallest nonzero mass.
/// Lengths enter the tracing up to their fourth power: Σ' = r⁴ + a²z² of the Kerr radius,
/// r₊ = M + √(M² − a²), M²/(r − 2M)² of the Schwarzschild splitting. Every point a ray visits
/// lies between r₊ ≥ M and the escape radius, so with all lengths in [1e-75, 1e75] every product
/// of four of them stays a normal double (2.2e-308 to 1.8e308) with a factor 1e8 to spare for
/// constant factors and sums; beyond, r₊ or r⁴ overflow to infinity or M² underflows to 0 (r₊
/// would then be M whatever the spin).
constexpr double kMaxSceneLength = 1e75;
constexpr double kMinSceneMass = 1e-75;

/// Checks every value of a description by the rules the scene file's fields follow (SceneFile.h),
/// in the file's order: the spacetime (finite, within the length bounds, a black hole:
/// makeSpacetime's rules); the camera (finite, within the bounds, a view angle in (0, 180), at
/// least one and at most kMaxFramePixels pixels, a focal point apart from the eye, a view-up off
/// the line of sight, outside the horizon, a static observer outside any ergosphere); the
/// integrator (a known method that can model the spacetime, positive finite step and
/// tolerances); the tracing tolerances; every celestial sphere within the bound and enclosing the
/// camera. Throws InvalidParameter naming the field as the scene file spells it
/// ("camera.position: ..."), so a value set after parsing (an override) is refused as the same
/// value in the file would be.
ASRTTRACING_EXPORT void validateScene(const SceneDescription& d);

/// The checks of validateScene by section, for the scene file's parser, which runs each once its
/// section is read (so that the first error in the file is the one reported).
ASRTTRACING_EXPORT void validateSpacetime(const SpacetimeParameters& p);
ASRTTRACING_EXPORT void validateCamera(const CameraParameters& c, const Spacetime& st);
ASRTTRACING_EXPORT void validateIntegrator(const IntegratorConfig& c, const Spacetime& st);
ASRTTRACING_EXPORT void validateTracing(const TraceOptions& t);
/// `field` names the radius (e.g. "objects[0].radius").
ASRTTRACING_EXPORT void validateCelestialSphere(double radius, const Vec3& eye,
                                                const std::string& field);
}

#endif
