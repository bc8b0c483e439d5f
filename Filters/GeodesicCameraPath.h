// A camera path through key cameras (eye, focal point, view-up per key), for movies whose
// viewpoint flies: read from a small JSON file and interpolated smoothly between the keys.
#ifndef asrt_GeodesicCameraPath_h
#define asrt_GeodesicCameraPath_h

#include "GeodesicMovie.h"
#include "asrtFiltersModule.h"

#include <string>
#include <vector>

namespace asrt
{
/// The key cameras of a JSON text {"keys": [{"position": [x, y, z], "focalPoint": [x, y, z],
/// "viewUp": [x, y, z]}, ...]}: at least two keys, every component a finite number, no other
/// field. Throws InvalidParameter naming the field ("keys[1].position[2]: ...") prefixed with
/// `name` (the file's).
ASRTFILTERS_EXPORT std::vector<CameraPose> parseCameraKeys(const std::string& text,
                                                           const std::string& name);

/// The camera at u in [0, K − 1] along K keys (key k at u = k): the eye, the focal point and
/// the view-up each on the uniform Catmull-Rom spline through the keys (C¹, through every key;
/// at the ends the missing neighbour is the key itself reflected, so the end tangents are the
/// chords'), the view-up normalised.
ASRTFILTERS_EXPORT CameraPose cameraOnPath(const std::vector<CameraPose>& keys, double u);

/// The camera through `keys` (at least 2) over `n` frames, frame k at u = (K − 1) k / (n − 1):
/// the first and last frames the first and last keys. Throws InvalidParameter for n outside
/// [2, kMaxMovieFrames] or fewer than 2 keys.
ASRTFILTERS_EXPORT MoviePath cameraKeyMoviePath(const std::vector<CameraPose>& keys, int n);
}

#endif
