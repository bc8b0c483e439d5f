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

#include "SceneDescription.h"
#include "asrtTracingModule.h"

#include <cstdint>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

namespace asrt
{
/// The largest scene a scene file or text may hold, in bytes (64 MiB): a scene is a few kB, and a
/// file read without bound (/dev/zero, an endless pipe) would take all memory.
constexpr std::size_t kMaxSceneBytes = std::size_t(64) << 20;
/// The deepest nesting of arrays and objects a scene's JSON may have (a scene needs 6). Deeper
/// documents are refused while parsing, before the nested value is built: printing or copying
/// nlohmann's values recurses once a level.
constexpr int kMaxSceneNesting = 64;
/// The most objects a scene may hold. A segment is tested only against the objects that the
/// scene's bounding-volume hierarchy cannot rule out (Scene.h), so objects spread through the
/// scene cost little each; but objects that overlap along a ray are each tested there, and
/// parsing grows with the square of the count (nlohmann's checked parse scans an array for
/// discarded values at the end of each element). README's limits give the costs measured at this
/// bound. Paper-like scenes hold a handful.
constexpr std::size_t kMaxSceneObjects = 20000;

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

/// Parses a scene from JSON text. Relative texture paths are resolved against `baseDir`; each
/// distinct image is read once through `loader` (which may be empty if no object uses an image).
/// Throws InvalidParameter with the offending field's path for any invalid, unknown or duplicate
/// field, unknown object type, unreadable texture, malformed JSON, text longer than
/// kMaxSceneBytes or nested deeper than kMaxSceneNesting; values and names quoted in its messages
/// are cut to a few dozen characters. Checks beyond single fields:
/// the spacetime (asrt::makeSpacetime's), the integration method against it (makePropagator's),
/// the camera outside the horizon and, for a static observer, outside any ergosphere, celestial
/// spheres enclosing the camera, frames of at most kMaxFramePixels pixels.
///
/// `origin` says whose text it is: a user's scene (a file, a string handed to a filter) may not
/// name a pixel subset, which only the program writes (effectiveSceneText of a subset frame);
/// the program's own texts, read back from the store, may.
enum class SceneOrigin
{
  User,
  Program
};
ASRTTRACING_EXPORT SceneDescription parseScene(const std::string& jsonText,
                                               const std::string& baseDir,
                                               const ImageLoader& loader,
                                               SceneOrigin origin = SceneOrigin::User);
/// The description as JSON, with its current spacetime, camera and integrator values (which may
/// have been changed since parsing, e.g. per movie frame) written over the parsed text: the scene
/// exactly as it is traced, for storage, hashing and re-tracing.
ASRTTRACING_EXPORT std::string effectiveSceneText(const SceneDescription& d);

/// An ImageLoader that reads nothing: every texture a 1×1 neutral grey, for a scene's identity and
/// text, never for rendering.
ASRTTRACING_EXPORT ImageLoader neutralImageLoader();

/// Parses a scene for what identifies and parameterises its frames (storage, hashing, re-reading),
/// without reading image textures: they become a neutral grey. Everything else is validated as by
/// parseScene, for a text of the program's (SceneOrigin::Program). Not for rendering.
ASRTTRACING_EXPORT SceneDescription parseSceneWithoutImages(const std::string& jsonText);

/// Reads and parses a scene file; its directory is the base for relative texture paths. Error
/// messages are prefixed with the file's path. The file is read in chunks and refused once it
/// exceeds kMaxSceneBytes, so that an endless file or pipe ends at that bound.
ASRTTRACING_EXPORT SceneDescription loadSceneFile(const std::string& path,
                                                  const ImageLoader& loader);
}

#endif
