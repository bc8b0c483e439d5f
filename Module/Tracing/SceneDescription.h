// What one frame is traced from: the spacetime, the camera, the scene's objects, the integrator
// and the tracing tolerances, and which pixels (all, or a subset). Reading and writing it as JSON
// is SceneFile.h's.
#ifndef asrt_SceneDescription_h
#define asrt_SceneDescription_h

#include "Camera.h"
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
  bool operator==(const PixelSubsetId& o) const
  {
    return this->count == o.count && this->digest == o.digest;
  }
};

/// The identity of a set of pixels: sorted and deduplicated first, so the order and repetitions
/// of the list do not matter. An empty list gives count 0 (a whole frame).
ASRTTRACING_EXPORT PixelSubsetId pixelSubsetId(std::vector<std::pair<int, int>> pixels);

struct SceneDescription
{
  std::string name;
  /// The hole: the scene file's "spacetime" (mass required there).
  SpacetimeParameters spacetime{ 1.0, 0.0, 0.0 };
  CameraParameters camera;
  IntegratorConfig integrator;
  TraceOptions tracing;
  std::shared_ptr<Scene> scene = std::make_shared<Scene>();
  /// Non-empty for a frame of only some pixels (the optional root field "subset": {"pixels": n,
  /// "digest": "..."}, written by the tools, not by hand).
  PixelSubsetId subset;
  /// The JSON it was parsed from, normalised: nlohmann's dump() of the parsed document (keys
  /// sorted, no whitespace), so equal documents give equal text (for storage and hashing).
  std::string sourceText;
};
}

#endif
