// A camera path through key cameras (eye, focal point, view-up per key), for movies whose
// viewpoint flies: read from a small JSON file and interpolated smoothly between the keys.
#ifndef asrt_tools_CameraPath_h
#define asrt_tools_CameraPath_h

#include "CameraOrbit.h"

#include <string>
#include <vector>

namespace asrt
{
namespace tools
{
/// The key cameras of a JSON text {"keys": [{"position": [x, y, z], "focalPoint": [x, y, z],
/// "viewUp": [x, y, z]}, ...]}: at least two keys, every component a finite number, no other
/// field. Throws InvalidParameter naming the field ("keys[1].position[2]: ...") prefixed with
/// `name` (the file's).
std::vector<CameraPose> parseCameraKeys(const std::string& text, const std::string& name);

/// The camera at u in [0, K − 1] along K keys (key k at u = k): the eye, the focal point and
/// the view-up each on the uniform Catmull-Rom spline through the keys (C¹, through every key;
/// at the ends the missing neighbour is the key itself reflected, so the end tangents are the
/// chords'), the view-up normalised.
CameraPose cameraOnPath(const std::vector<CameraPose>& keys, double u);
}
}

#endif
