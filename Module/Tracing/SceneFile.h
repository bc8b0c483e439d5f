// Scene descriptions as JSON files: spacetime, camera, objects, integrator and tolerances. Every
// field is validated; errors name the field ("objects[2].radius: must be positive, got -1").
// The format is documented in Data/scenes/README.md:
//   {"name", "description", "spacetime": {mass, spin, charge},
//    "camera": {position, focalPoint, viewUp, viewAngle (degrees), resolution [w, h], observer},
//    "integrator": {method, step, timeTransform, omega, relativeTolerance, absoluteTolerance},
//    "tracing": {escapeRadius, maxSteps, horizonEpsilon, maxHamiltonianError},
//    "background": [r, g, b], "horizonColor": [r, g, b],
//    "objects": [{type, id, name, texture: {color | checker + colors | image}, ...geometry}]}
// Unknown and duplicate keys are errors, so that a typo never silently leaves a default in place.
#ifndef asrt_SceneFile_h
#define asrt_SceneFile_h

#include "Camera.h"
#include "RayTracer.h"
#include "Scene.h"
#include "asrtTracingModule.h"

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace asrt
{
/// Pixels of an image file: RGB, 8 bits a channel, row-major, row 0 at the bottom (VTK's order).
struct ImagePixels
{
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> rgb;
};

/// Reads an image file. The numeric core reads none itself: the VTK layer passes one built on
/// VTK's image readers. It throws InvalidParameter if the file is missing or unreadable.
using ImageLoader = std::function<ImagePixels(const std::string& path)>;

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
  double mass = 1.0;
  double spin = 0.0;
  double charge = 0.0;
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

/// Parses a scene from JSON text. Relative texture paths are resolved against `baseDir`; each
/// distinct image is read once through `loader` (which may be empty if no object uses an image).
/// Throws InvalidParameter with the offending field's path for any invalid, unknown or duplicate
/// field, unknown object type, unreadable texture or malformed JSON. Checks beyond single fields:
/// the spacetime (asrt::makeSpacetime's), the integration method against it (makePropagator's),
/// the camera outside the horizon and, for a static observer, outside any ergosphere, celestial
/// spheres enclosing the camera, frames of at most 2²⁸ pixels.
ASRTTRACING_EXPORT SceneDescription parseScene(const std::string& jsonText,
                                               const std::string& baseDir,
                                               const ImageLoader& loader);
/// The description as JSON, with its current spacetime, camera and integrator values (which may
/// have been changed since parsing, e.g. per movie frame) written over the parsed text: the scene
/// exactly as it is traced, for storage, hashing and re-tracing.
ASRTTRACING_EXPORT std::string effectiveSceneText(const SceneDescription& d);

/// Parses a scene for what identifies and parameterises its frames (storage, hashing, re-reading),
/// without reading image textures: they become a neutral grey. Everything else is validated as by
/// parseScene. Not for rendering.
ASRTTRACING_EXPORT SceneDescription parseSceneWithoutImages(const std::string& jsonText);

/// Reads and parses a scene file; its directory is the base for relative texture paths. Error
/// messages are prefixed with the file's path.
ASRTTRACING_EXPORT SceneDescription loadSceneFile(const std::string& path,
                                                  const ImageLoader& loader);
}

#endif
