// Planning a movie along a path: which frames to trace as key frames, and for every other frame
// the cheaper of interpolating it between its keys (with the pixels it must re-trace to meet the
// quality target) and tracing it whole. Costs are in rays integrated, whole frames and re-traces
// alike (MovieCostModel); a frame already stored costs nothing and is a key for free.
//
// The planner knows nothing of how the re-trace share is estimated: it is handed a function of
// the two keys' parameters and the frame's (RetraceShare). SpacingShareModel is one such estimate,
// proportional to the keys' spacing and corrected by measured frames.
//
// Keys. The first and last frames are keys (nothing extrapolates), and so is every stored frame.
// Between two neighbouring keys i < j the segment costs the smaller of
//   - no further key: every frame between costs the smaller of interpolating it (its re-trace at
//     the share estimated for that frame between i and j, and the interpolation) and tracing it
//     whole (a share ≥ 1, infinite or NaN: the pair cannot meet the target there, so the frame is
//     traced);
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

/// What making a movie costs, in rays integrated (FrameTracer::raysIntegrated), the unit of a
/// whole frame and of a re-trace alike. A whole frame at s costs wholeRays(s). An interpolated
/// frame at s costs interpolatedRays(s, share): re-tracing that share of its pixels (their own
/// rays, and their edge neighbours, edge midpoints and anti-aliasing samples: RetraceRays.h) and
/// interpolating it. It is traced whole instead when that is not below wholeRays(s).
struct MovieCostModel
{
  double frameRays = 0; ///< rays a whole frame takes (pixels × rays per pixel, or a key's count)
  /// The rays a whole frame at path parameter s takes (those measured around s); empty, or not
  /// positive and finite there: frameRays.
  std::function<double(double s)> wholeRaysAt;
  /// Rays of re-tracing every pixel one by one, as a share's cost where retraceRaysAt is empty:
  /// share · retraceRays. 0: frameRays.
  double retraceRays = 0;
  /// The rays of re-tracing this share of the pixels of the frame at s; empty, or not finite and
  /// non-negative there: share · retraceRays.
  std::function<double(double s, double share)> retraceRaysAt;
  /// Interpolating a frame (predicting, estimating and completing its pixels), as the rays its
  /// CPU time would trace.
  double interpolationRays = 0;
  RetraceShare retraceShare;
  /// The rays of a whole frame at s.
  double wholeRays(double s) const;
  /// The rays of interpolating a frame at s with this share re-traced, or NaN when it cannot (a
  /// share outside [0, 1), infinite or NaN).
  double interpolatedRays(double s, double share) const;
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
  double estimatedRays = 0;     ///< the plan's estimated cost, in rays
  double directRays = 0;        ///< tracing every frame not stored
  double tracedAllRays = 0;     ///< tracing every frame, stored or not
  double frameRays = 0;         ///< the rays of a whole frame the estimates counted
  double retraceRays = 0;       ///< the rays of re-tracing every pixel they counted (0: frameRays)
  double interpolationRays = 0; ///< interpolating a frame, in rays
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

/// The keys of `keys` (sorted, distinct) that interpolating frame k between them uses: the
/// nearest 4, two on either side where there are two, and at an end of the keys the 4 there (or
/// all, where there are fewer). At an end the key beyond the inner pair's outer neighbour does
/// not join the prediction but measures the quadratic's error against the cubic through it
/// (PathInterpolation.h), as vtkGeodesicPathInterpolator, given every key, measures it.
ASRTINTERPOLATION_EXPORT std::vector<int> keysAround(const std::vector<int>& keys, int k);

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
/// The slope is a prior until frames are measured; observe() makes it the mean measured slope
/// (a pair that re-traced the whole frame bounds the slope from below only).
/// How fast edges move changes along a path (a ramp of mass barely moves them while the hole is
/// small), so a measurement also stands for its own stretch: keys inside a measured pair take the
/// slope of the narrowest measured pair around them, the mean slope only elsewhere.
struct SpacingShareModel
{
  double pathLength = 1;
  double floor = 0.01;
  double slope = 1; ///< the share re-traced with keys a whole path apart, beyond the floor
  double measuredSlopeSum = 0;
  int measured = 0;
  struct Measurement
  {
    double keyA = 0, keyB = 0, slope = 0;
    bool saturated = false; ///< it re-traced everything: the slope is a lower bound
  };
  std::vector<Measurement> measurements;

  double share(double keyA, double keyB) const;
  /// A frame interpolated between keys at keyA and keyB re-traced this share.
  void observe(double keyA, double keyB, double share);
  RetraceShare function() const;
};

/// What planning a movie progressively asks of the movie. makeWhole traces (or reads) frame k
/// whole and returns the rays it took. measureShare interpolates whole frame k between the whole
/// frames `before` and `after` (and those beyond them, as a movie's frame would be) and completes
/// it to the target against frame k's own records, which it already has: the share of pixels the
/// target needed re-traced, and the rays re-tracing them at k would take (RetraceRays.h),
/// measured without tracing a ray.
struct ShareMeasurement
{
  double share = 0;
  double raysPerPixel = 1;  ///< the re-traced pixels' own rays, per pixel; 0 when none
  double neighbourRays = 0; ///< their edge neighbours' centre rays
  double edgeRays = 0;      ///< edge midpoints and the pixels' anti-aliasing samples
};
/// What a movie's costs are taken to be before they are measured, in rays per pixel of a frame.
struct MovieCostPrior
{
  double wholeRaysPerPixel = 1; ///< a whole frame
  /// An interpolated frame's re-trace beyond its pixels' own rays (one each).
  double edgeRaysPerPixel = 0;
  /// Interpolating a frame, as rays: not measured (a time), the same all along the movie.
  double interpolationRaysPerPixel = 0;
  /// The model of a movie of frames of `pixels` pixels.
  MovieCostModel model(double pixels, const RetraceShare& share) const;
};
struct KeyMaking
{
  std::function<double(int k)> makeWhole;
  std::function<ShareMeasurement(int k, int before, int after)> measureShare;
};

/// Plans the movie and makes its whole frames, learning the costs as it goes. The keys are made
/// coarse first: of the plan's whole frames not yet made, the one nearest the middle of the
/// widest gap between frames already whole. Each key made is measured (measureShare between the
/// whole frames around it), which gives the share the gap around it needed for its key spacing
/// and what its re-trace would cost; frames made because interpolating them costs more are not
/// (their measurement, an interpolation, would cost as much as what it saved). With the rays the
/// whole frames took, the rest of the movie is planned again with the frames made as stored
/// ones. The costs are local, linear in s between the measured frames around s: a whole frame
/// costs what those took, and re-tracing a share σ their re-traces scaled to σ (the pixels' own
/// rays in proportion; their edge neighbours as √σ, the perimeter of patches that grow; the
/// edge midpoints and samples as they are, the edges' own). frameRays is the mean of the frames
/// made. Frames made stay made. `share` starts as the prior and ends holding every measurement;
/// `pixels` is a frame's pixel count, and `prior` the costs before any is measured. Returns the
/// final plan, whose whole frames are all made: stored ones Reused, the others Key or Traced.
/// Frames stored already (an earlier run's keys) are measured first, each between the stored
/// frames around it: the prior of a movie over a path stored before. Throws as planMovie does.
ASRTINTERPOLATION_EXPORT MoviePlan planProgressively(const std::vector<double>& s,
                                                     const std::vector<bool>& stored, double pixels,
                                                     SpacingShareModel& share,
                                                     const KeyMaking& making,
                                                     const MovieCostPrior& prior = {});
}

#endif
