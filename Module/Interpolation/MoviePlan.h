// Planning a movie along a path: which frames to trace as key frames, and for every other frame
// the cheaper of interpolating it between its keys (with the pixels it must re-trace to meet the
// quality target) and tracing it whole. Costs are in rays traced; a frame already stored costs
// nothing and is a key for free.
//
// The planner knows nothing of how the re-trace share is estimated: it is handed a function of
// the two keys' parameters and the frame's (RetraceShare). SpacingShareModel is one such estimate,
// proportional to the keys' spacing and corrected by measured frames.
//
// Keys. The first and last frames are keys (nothing extrapolates), and so is every stored frame.
// Between two neighbouring keys i < j the segment costs the smaller of
//   - no further key: every frame between costs min(share · rays, rays), share the estimate for
//     that frame between i and j (a share ≥ 1, infinite or NaN: the pair cannot meet the target
//     there, so the frame is traced);
//   - a key at the middle frame m (its rays, nothing if stored) plus the best of (i, m) and (m, j).
// Each sub-segment of the bisection is evaluated once: O(n log n) estimates for n frames. Since
// every frame's cost is at most its rays and every key is a frame traced, the plan never costs
// more than tracing every frame, by its own estimate.
//
// Stability. A frame traced whole (a key, or one traced because interpolating it costs more) is
// stored whole, so the next run of the same movie finds it stored. The plan is therefore made
// with its own whole frames as stored ones until that adds no more: planned again with every
// frame it traces whole stored, the movie has the same keys and interpolates the same frames
// between the same keys (which is what makes a second run trace nothing). Frames traced because
// interpolating costs more are keys too.
//
// More frames on the same path. A denser movie over a path stored before (twice the frames:
// every old frame is a frame of the new one) costs the bisection more to interpolate, so it may
// add keys; but a new key changes the keys of the old interpolated frames near it, whose stored
// re-traced pixels then no longer serve. planBetweenStored() is the other candidate: the stored
// frames as the only keys, every other frame interpolated between the stored frames around it,
// and the frames the caller knows to be served whole by the store at those keys costing nothing.
// The caller takes the cheaper; when the stored frames are all an earlier plan's keys and its
// frames are all served, that is the earlier movie's plan with the new frames between.
#ifndef asrt_MoviePlan_h
#define asrt_MoviePlan_h

#include "asrtInterpolationModule.h"

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace asrt
{
/// The share of a frame's pixels that interpolating it at `s` between keys at `keyA` and `keyB`
/// re-traces for the quality target (must-retrace pixels, probes and chosen ones), in [0, 1];
/// anything ≥ 1, infinite or NaN means the pair cannot make the frame for less than tracing it.
using RetraceShare = std::function<double(double keyA, double keyB, double s)>;

/// How a frame of the movie is made.
enum class FrameMethod : std::uint8_t
{
  Reused = 0,      ///< already stored whole: read, not traced (a key for free)
  Key = 1,         ///< traced whole and used as a key
  Traced = 2,      ///< traced whole because interpolating it would cost more (then a key too)
  Interpolated = 3 ///< interpolated between its keys, the pixels the target needs re-traced
};
ASRTINTERPOLATION_EXPORT const char* toString(FrameMethod m);

/// What making a movie costs: the rays of one traced frame, and the re-trace share estimate.
struct MovieCostModel
{
  double frameRays = 0; ///< rays a whole frame takes (pixels × rays per pixel, or a key's count)
  RetraceShare retraceShare;
};

struct FramePlan
{
  FrameMethod method = FrameMethod::Key;
  int keyBefore = -1, keyAfter = -1; ///< the keys bracketing an interpolated frame
  double share = 0;                  ///< estimated share re-traced (1 for traced, 0 for reused)
  double rays = 0;                   ///< estimated rays
};

struct MoviePlan
{
  std::vector<FramePlan> frames;
  double estimatedRays = 0; ///< the plan's estimated cost, in rays
  double directRays = 0;    ///< tracing every frame not stored
  double tracedAllRays = 0; ///< tracing every frame, stored or not
  /// The keys in order: every frame not interpolated.
  std::vector<int> keys() const;
};

/// Plans the movie of frames at path parameters `s` (strictly monotonic, at least one frame),
/// `stored[k]` telling which are stored whole already (same size as `s`, or empty: none).
/// Throws InvalidParameter naming what is wrong: parameters not finite or not strictly monotonic,
/// a size mismatch, frameRays not positive and finite, or no retraceShare.
ASRTINTERPOLATION_EXPORT MoviePlan planMovie(const std::vector<double>& s,
                                             const std::vector<bool>& stored,
                                             const MovieCostModel& model);

/// The plan whose keys are exactly the stored frames: every other frame interpolated between the
/// stored frames before and after it, at no cost where `served[k]` (its re-traced pixels are
/// stored for those keys already), else at its estimated share. None when the first or last
/// frame is not stored, or a frame's estimate between its stored neighbours is not below 1 (it
/// would be traced, and so become a key). `served` is empty (none) or one flag per frame. Throws
/// InvalidParameter as planMovie does.
ASRTINTERPOLATION_EXPORT std::optional<MoviePlan> planBetweenStored(const std::vector<double>& s,
                                                                    const std::vector<bool>& stored,
                                                                    const std::vector<bool>& served,
                                                                    const MovieCostModel& model);

/// The re-trace share as a function of the keys' spacing: floor + slope · |keyB − keyA| /
/// pathLength, where the floor is the probes' share. Between two keys, the pixels an
/// interpolation cannot vouch for are those whose rays change how they end (an edge of an object,
/// of the shadow, of an image) between the keys, and their neighbours: a band along each edge as
/// wide as the edge moves between the keys, so proportional to their spacing while it is small.
/// The slope is a prior until frames are measured; observe() makes it the mean measured slope.
struct SpacingShareModel
{
  double pathLength = 1;
  double floor = 0.01;
  double slope = 1; ///< the share re-traced with keys a whole path apart, beyond the floor
  double measuredSlopeSum = 0;
  int measured = 0;

  double share(double keyA, double keyB) const;
  /// A frame interpolated between keys at keyA and keyB re-traced this share.
  void observe(double keyA, double keyB, double share);
  RetraceShare function() const;
};
}

#endif
