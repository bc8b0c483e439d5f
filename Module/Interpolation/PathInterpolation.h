// Frames between key frames of a movie path, interpolated per pixel in the path's parameter s (a
// mass, a spin, an orbit angle): a pixel's ray record is a smooth function of s until its ray
// changes topology (another object, another way of ending, another image), so each pixel is
// predicted from its own records in the nearest key frames, then re-shaded.
//
//  - Nodes. The inner pair of keys brackets t. If their records of the pixel end alike (object,
//    termination, a winding that is continuous between them), the outer neighbours join when they
//    end alike too: 4 nodes give a cubic Lagrange prediction, 3 a quadratic, 2 a linear one. At
//    an end of the keys, where one side has no outer neighbour, the second key beyond on the
//    other side measures the quadratic's error where it ends alike (callers pass the keys around
//    t: the nearest 4 where there are 4). Otherwise the keys cannot vouch for the
//    pixel, nor for its 8 neighbours (an edge that moves between the keys may cross them at t):
//    these are predicted by moving the keys' scene points across the picture (PathEdges.h,
//    PathMethod::MovedEdge, or MovedSurface where no edge lies within a pixel of the pixel at t),
//    and re-traced where no moved point covers them (or, without PathOptions::movedEdges, all
//    re-traced).
//  - Chains. Frames between the keys that were traced in part (PathSamples: the pixels another
//    frame re-traced) hold exact records of some pixels nearer t than the keys. A pixel the inner
//    keys cannot vouch for is predicted from its chain of records, the keys' and those, in order
//    of s: the nearest record on either side of t is its inner pair, and the outer ones join as
//    above. It is vouched for where its inner pair is two single rays that end alike, and each of
//    its 8 neighbours either ends alike in the same two frames or is one the keys vouch for (an
//    edge that crossed the pixel between the inner pair would show on one of them). Its estimate
//    is a prediction's, from the chain; the keys' leave-one-out errors do not weigh it (they
//    measure the keys' spacing, not the chain's). An edge pixel (an inner record supersampled) is
//    left to be re-traced: blended through its chain as a key's edge pixel is (below), it cost a
//    mass ramp's frames at 48 × 48 up to 4 dB against the traced ones, unseen by the estimate.
//  - Winding. floor(winding/π), the image order, flips smoothly for escaping rays as a hole grows;
//    a new image of an object instead shows as a jump of the winding between keys (a ray that now
//    passes the hole on its other side, or goes once more round it). So continuity is judged on
//    the winding itself: keys whose windings differ by less than kWindingJump end alike.
//  - Fields. u is taken the short way round from the nearest node's u, then wrapped into [0, 1);
//    v, the Jacobians ∂(u, v)/∂(i, j), the hit point and normal, the path length and winding, and
//    the initial ray are interpolated with the same weights. The colour is the texture filtered
//    over the interpolated footprint (Scene::shadeFootprint), as a traced pixel's is.
//  - Edges. A pixel that either inner key supersampled (an edge runs through it) but whose centre
//    rays end alike shows the average over the edge's two sides, which varies with s as the edge
//    moves inside it: its centre ray is predicted and re-shaded as any pixel's, and what the keys'
//    colours add to their centre rays' shades (the other side's share) is interpolated
//    (EdgeBlend); the estimate is at least the keys' colour step, and where the two inner keys
//    alone end alike there, the nearer key's contrast with its 4 neighbours (what the edge moving
//    by a pixel changes; with 3 or 4 keys, the edge stayed within reach of the pixel).
//  - Estimate. The colour of the prediction of one order lower (the outer node farther from t
//    dropped; for a linear prediction, the nearer key) differs from the prediction by about the
//    lower order's error; at an end of the keys, one order higher (the key beyond joining)
//    differs from the quadratic by about the quadratic's own: that squared difference, summed over
//    the channels in levels² of 255, ranks the pixels for re-tracing. Two orders may land on like
//    colours while a bright feature of the texture lies just beside them (keys far apart move a
//    pixel across many texels), so the texture is also sampled one disagreement in (u, v) further
//    on and to either side (one side alone where the disagreement is a quarter of a pixel or less,
//    where the filtered colour is linear across it and the other two samples say what the lower
//    order and that side do). A linear prediction's estimate is also at least the squared colour
//    step between its keys. A moved edge's estimate is the disagreement of the other ways of moving
//    the scene points, and of the pixel's own prediction where there is one, with the prediction
//    (PathEdges.h).
// Plain C++ with OpenMP over rows; the result does not depend on the number of threads.
#ifndef asrt_PathInterpolation_h
#define asrt_PathInterpolation_h

#include "FrameMatching.h"
#include "KeptResults.h"
#include "RayRecord.h"
#include "Scene.h"
#include "asrtInterpolationModule.h"

#include <cmath>
#include <cstdint>
#include <functional>
#include <list>
#include <memory>
#include <mutex>
#include <utility>
#include <vector>

namespace asrt
{
class FrameTracer;
class LeaveOneOutCache;
class Spacetime;

/// Windings of one pixel in two keys that differ by this much or more are a change of image.
constexpr double kWindingJump = 0.5 * M_PI;

/// The spacetime of a path's frame at s.
using SpacetimeAlongPath = std::function<std::shared_ptr<const Spacetime>(double s)>;

/// One key frame of a path: its parameter and its records, one per pixel, row-major from the
/// bottom-left (record k is pixel (k mod width, k / width)).
struct PathKey
{
  double s = 0;
  const std::vector<RayRecord>* records = nullptr;
  /// matchingFingerprint(*records), where the caller keeps it for keys it passes again and again
  /// (0: computed where it is needed).
  std::uint64_t fingerprint = 0;
};

/// Some pixels of a frame of the path traced at s: the pixels a frame between keys re-traced. Their
/// records are exact, as a key's are, and join each of those pixels' chain of nodes beside the
/// keys' (PathOptions::samples).
struct PathSamples
{
  double s = 0;
  std::vector<std::int32_t> pixels; ///< strictly ascending pixel indices, j · width + i
  std::vector<RayRecord> records;   ///< one per pixel, in that order
};

/// How a pixel of a path frame got its record.
enum class PathMethod : std::uint8_t
{
  Key = 0,       ///< t is a key's parameter: the key's record itself
  Cubic = 1,     ///< 4 nodes
  Quadratic = 2, ///< 3 nodes
  Linear = 3,    ///< 2 nodes
  Retrace = 4,   ///< the keys cannot vouch for it: to be traced (its record is the nearer key's)
  Retraced = 5,  ///< traced at t
  EdgeBlend =
    6, ///< an edge pixel: its centre ray predicted, the keys' colour beyond it interpolated
  MovedEdge = 7, ///< near an edge the inner keys disagree on: from the keys' scene points, moved
  /// As MovedEdge, but the moved points within a pixel of it all end alike: no edge lies there at
  /// t (calibrated apart from the pixels an edge crosses)
  MovedSurface = 8
};
constexpr int kPathMethodCount = 9;
ASRTINTERPOLATION_EXPORT const char* toString(PathMethod m);

/// Whether a pixel got its record by a way of predicting: neither a key's, nor traced at t, nor
/// still to be traced.
inline bool isPrediction(std::uint8_t m)
{
  return m != static_cast<std::uint8_t>(PathMethod::Retrace) &&
         m != static_cast<std::uint8_t>(PathMethod::Key) &&
         m != static_cast<std::uint8_t>(PathMethod::Retraced);
}

/// What a key frame shows at a pixel: the surface, and how its ray ended there.
struct PathSurface
{
  std::int32_t objectId = -1;
  Termination termination = Termination::Running;
  double winding = 0;
};

/// A record's surface: its object, termination and winding.
inline PathSurface surfaceOf(const RayRecord& r)
{
  return { r.objectId, r.termination, r.winding };
}

/// Whether two pixels show the same surface the same way: the same object, the same termination
/// and a winding continuous between them.
inline bool sameSurface(const PathSurface& a, const PathSurface& b)
{
  return a.objectId == b.objectId && a.termination == b.termination &&
         std::abs(a.winding - b.winding) < kWindingJump;
}

/// A frame at parameter t of a path.
struct PathFrame
{
  int width = 0, height = 0;
  double t = 0;
  std::vector<RayRecord> records;
  /// Per pixel, the estimated squared colour error summed over the channels (levels² of 255);
  /// infinite where the pixel must be re-traced, 0 for keys and re-traced pixels.
  std::vector<float> estimate;
  std::vector<std::uint8_t> method; ///< PathMethod per pixel
  /// Per pixel, what the inner pair of keys around t show (empty for a key): the edges the keys
  /// saw, which completePathFrame holds the edges traced at t against.
  std::vector<PathSurface> innerKeys[2];
  /// Whether the estimates were weighed by the keys' leave-one-out errors (PathOptions::
  /// leaveOneOut, where a key could be left out): they then rank the edge blends, whose scale
  /// completePathFrame holds at a sixteenth rather than 1 (estimateScale).
  bool leaveOneOutWeighed = false;
  /// Pixels per PathMethod.
  std::vector<std::size_t> counts() const;
};

/// Squared colour difference summed over the channels, in levels² of 255: the unit of a path
/// frame's estimate.
inline float colorError2(const Color& a, const Color& b)
{
  const Color d = 255.0 * (a - b);
  return static_cast<float>(d.squaredNorm());
}

/// Lagrange weights w[k] of the nodes s[0..n) at t: Σ w[k] f(s[k]) is the polynomial of degree
/// n − 1 through the nodes, at t. The nodes must be distinct; 1 ≤ n ≤ 4.
ASRTINTERPOLATION_EXPORT void lagrangeWeights(const double* s, int n, double t, double* w);

/// Whether two records of one pixel end alike: the same object, the same termination, a winding
/// continuous between them (|Δwinding| < kWindingJump), and a ray that ended cleanly (escaped,
/// captured or on an object).
ASRTINTERPOLATION_EXPORT bool endAlike(const RayRecord& a, const RayRecord& b);

/// The record of one pixel predicted from its records at the given nodes (1 to 4, distinct s,
/// all ending alike): the fields the header lists, interpolated at t; the colour is left to the
/// caller (shadePrediction). The pixel, termination and object are the first node's.
ASRTINTERPOLATION_EXPORT RayRecord predictRecord(const RayRecord* const* nodes, const double* s,
                                                 int n, double t);

/// The colour a traced pixel with this record would show with one ray: the object's texture
/// filtered over the record's footprint (point-sampled where the footprint is undefined), or the
/// horizon's, the background's or the failure colour.
ASRTINTERPOLATION_EXPORT Color shadePrediction(const Scene& scene, const RayRecord& r);

/// The correspondences between key frames that the moved edges match (the inner pair, and each
/// inner key with its outer neighbour), kept for the frames that follow: every frame between the
/// same keys, and the next pair's frames, match the same pairs again. Kept by the content of the
/// keys' records (a fingerprint of every field the matching reads), so that a key read again, or
/// a buffer reused for another frame, is never taken for another. At most `capacity` are kept
/// (each 2 × 32 bytes a pixel: 133 MB at 1920×1080), the least recently used going first.
/// Thread-safe.
class ASRTINTERPOLATION_EXPORT PathMatchCache
{
public:
  explicit PathMatchCache(std::size_t capacity = 3);
  /// The correspondence of the frames whose records have fingerprints `a` and `b`
  /// (matchingFingerprint, keyFingerprint), `match()` where none is kept.
  std::shared_ptr<const Correspondence> matches(std::uint64_t a, std::uint64_t b,
                                                const std::function<Correspondence()>& match);
  /// How many correspondences `matches` made (rather than found kept) so far.
  std::size_t made() const;

private:
  /// By the fingerprints of the two frames' records.
  KeptResults<std::pair<std::uint64_t, std::uint64_t>, Correspondence> Kept;
};

/// A fingerprint of the fields of a frame's records that its matching reads (pixel, hit point,
/// surface coordinates and their Jacobian, path length, object, image order, termination, colour,
/// direction): equal records, equal fingerprints; different ones, different fingerprints but for
/// a collision of 64-bit hashes.
ASRTINTERPOLATION_EXPORT std::uint64_t matchingFingerprint(const std::vector<RayRecord>& records);

/// A key's matchingFingerprint: the one its caller kept (PathKey::fingerprint), else made now.
ASRTINTERPOLATION_EXPORT std::uint64_t keyFingerprint(const PathKey& key);

/// How interpolateAlongPath predicts.
struct PathOptions
{
  /// Predict the pixels near an edge that the inner keys disagree on by moving the keys' scene
  /// points (PathMethod::MovedEdge), instead of leaving them all to be re-traced.
  bool movedEdges = true;
  /// The nearest-point search that matches the keys' scene points (matchFrames) for the moved
  /// edges: the caller's, as for matchFrames (the filters pass asrt::kdTreeIndexFactory()).
  /// Required when movedEdges is set.
  PointIndexFactory pointIndex;
  /// A moved edge's colour is the mean of the ways of moving the keys' points that cover the
  /// pixel, not that of both inner keys' points alone (PathEdges.h, Hedging).
  bool hedgeMovedEdges = true;
  /// The share of the inner keys' own residual that a moved pixel an edge crosses takes: each
  /// key's traced colour less what its own points show at its pixel's sub-positions, carried to
  /// t with the points that cover the pixel (PathEdges.h, The keys' own residual). 0: none.
  double keyResidualShare = 0.6;
  /// Where a surface's moved points and the hole's cover the same spot, the spot is the mean of
  /// their colours (PathEdges.h, the shadow's rim): for a frame shown as predicted, the plain
  /// preview. Not for one completed to a target (completePathFrame): on the mass ramp, keys
  /// 0.11 M apart, a frame completed to 35 dB from it scored 33.4 dB against the traced frame
  /// (39.9 without), its estimate missing what the mean leaves.
  bool hedgeNearShadow = false;
  /// The path's spacetime at s, where the caller knows it (empty, or null at s: not known; called
  /// for t and the inner keys' s, from the calling thread). A scene point the
  /// moved edges would show at t that lies inside the hole's outer horizon at t is not shown
  /// there: a hole that grows along the path swallows the surfaces that reach into it
  /// (PathEdges.h, The horizon).
  SpacetimeAlongPath spacetimeAt;
  /// Where the moved edges' correspondences are kept between frames (null: each frame matches
  /// its keys afresh). The frames are the same either way.
  std::shared_ptr<PathMatchCache> matchCache;
  /// Weigh each predicted pixel's estimate by how well the keys predict each other there
  /// (LeaveOneOut.h): where an inner key, left out, is badly predicted from the other keys,
  /// the frame between them is likely badly predicted too. Needs a key beyond each inner key
  /// that is left out; without one the estimate is as it is.
  bool leaveOneOut = true;
  /// Estimate each pixel's error (PathFrame::estimate). Off, the pixels predicted per pixel get
  /// an estimate of 0 and the frame is made without the shading the estimate takes (four more
  /// texture samples a pixel): the colours are the same. A key left out needs its colours alone.
  bool estimates = true;
  /// Where the keys' leave-one-out errors are kept between frames (null: made afresh for each).
  /// The frames are the same either way.
  std::shared_ptr<LeaveOneOutCache> leaveOneOutCache;
  /// Frames of the path traced in part (the pixels other frames between the keys re-traced), at
  /// parameters other than t and the keys'. A pixel the inner keys cannot vouch for is predicted
  /// from its own records, the keys' and these, where the nearest two around t end alike: what an
  /// edge did between the keys, records nearer t may show it did not do there (the Chains
  /// paragraph of this header). Samples outside the inner keys are not read.
  std::vector<std::shared_ptr<const PathSamples>> samples;
};

/// The frame at t from the keys (at least 2, their s strictly increasing, t within
/// [s_first, s_last], every key `width` × `height` records of the same pixels). Throws
/// InvalidParameter naming what is wrong, also for moved edges without a point index.
ASRTINTERPOLATION_EXPORT PathFrame interpolateAlongPath(const std::vector<PathKey>& keys, double t,
                                                        int width, int height, const Scene& scene,
                                                        const PathOptions& options);

/// The colours of interpolateAlongPath's frame at t without moved edges and estimates
/// (PathOptions::movedEdges and estimates off), the same bit for bit, and nothing else: for what
/// reads the colours alone (the keys left out, LeaveOneOut.h). It skips what the frame's records,
/// estimates and methods cost: a whole record written per pixel, and the shading of the lower
/// orders. Throws as interpolateAlongPath does.
ASRTINTERPOLATION_EXPORT std::vector<Color> interpolatedColours(const std::vector<PathKey>& keys,
                                                                double t, int width, int height,
                                                                const Scene& scene);

/// What completing a path frame for a quality target did.
struct PathCompletion
{
  std::size_t mustRetrace = 0; ///< pixels the keys could not vouch for
  /// Pixels traced because a traced neighbour showed another surface than their prediction.
  std::size_t followed = 0;
  std::size_t retraced = 0; ///< pixels traced at t in all (the above, chosen ones and probes)
  std::size_t probes = 0;   ///< pixels traced to measure the estimate's scale
  /// Pixels traced with the converged rendering where the keys' settings fell short of the
  /// target (SettingsRefinement, SettingsError.h); some of them traced before with the keys'.
  std::size_t refined = 0;
  /// Of the completed frame: against the converged picture, the error left untraced plus the
  /// settings' own (settingsMse); against the frame traced at t where that is 0.
  double estimatedPsnr = 0;
  /// Rays integrated to trace them, as the pixel tracer counted them: with a FrameTracer, every
  /// ray it integrated (FrameTracer::raysIntegrated), the edge neighbours traced and dropped
  /// included, and a pixel traced again where a later list borders it.
  double raysTraced = 0;
};

/// How completePathFrame scales a way of predicting's estimates by its probes.
enum class EstimateScaling : std::uint8_t
{
  /// The probes' true error over their estimates (Cochran's ratio estimate) raised by two of its
  /// standard errors; at least 1 for moved edges across an edge, whose errors are rare and large,
  /// and for edge blends unless the keys' leave-one-out errors rank them.
  Ratio = 0,
  /// The probes' true error over their estimates, at least 1 for every way: the estimate only
  /// ever scaled up.
  AtLeastOne = 1
};

/// A probe's estimate and its true error (squared colour errors summed over the channels).
struct ProbePair
{
  double estimate = 0, error = 0;
};

/// The scale of way `m`'s estimates from its probes. Ratio: Cochran's ratio estimate
/// R = Σ error / Σ estimate raised by two of its standard errors,
/// sqrt(Σ (error − R·estimate)² / (n − 1) / n) / mean estimate (Cochran, Sampling Techniques,
/// 3rd ed., § 6.3), at least 1 for moved edges (PathMethod::MovedEdge) and at least 1/1024 for the
/// others (their order of re-tracing kept where every probe came out exact). Edge blends' errors
/// are rare and large too: at least 1 for them as well, or, where `edgeBlendsRanked` (the
/// estimates were weighed by the keys' leave-one-out errors, LeaveOneOut.h), at least 1/16: their
/// probes still miss the rare large errors at times (bench/REPORT.md, "Movies": without it, frames
/// of the mass ramp and the Kerr orbit at 40 dB fell 1.4–1.5 dB below their target). So do linear
/// pixels' (two keys alone agree): at least 1/16 for them. Every way at least 3/n for n probes:
/// n probes that erred little do not show its large errors to be rarer than that (the rule of
/// three).
/// AtLeastOne: R, at least 1.
/// 1 where the probes' estimates sum to 0 (or there are none).
ASRTINTERPOLATION_EXPORT double estimateScale(PathMethod m, const std::vector<ProbePair>& probes,
                                              EstimateScaling scaling,
                                              bool edgeBlendsRanked = false);

/// Re-traces, with `tracer` (the scene at t, the frame's size), the pixels that must be re-traced,
/// then, worst estimate first, just enough more for the completed frame's estimated PSNR against
/// the frame traced at t to reach `targetDb`. The estimate's scale is calibrated by probes, a
/// fixed pseudo-random `probeFraction` of the pixels (at least 64) traced at t, topped up to at
/// least 32 pixels of every way of predicting (cubic, quadratic, linear, edge blend, moved edge,
/// moved surface): per way, as `scaling` says. What the chosen pixels leave untraced is bounded per
/// way of predicting by the larger of its calibrated estimates and its probes placed at or below
/// them in the order (at least 16): their mean error plus two standard errors, with one more probe
/// of the way's typical error counted in, since probes that all came out exact show only that
/// errors are rare. The estimated PSNR is infinite only when nothing predicted is left. Re-traced
/// records are the full frame's, bit for bit (FrameTracer::tracePixels). Where a pixel traced at t
/// (a must-retrace pixel, a probe, or one traced for the reason that follows) shows another surface
/// than its own prediction and than the prediction of a neighbour (8-neighbours), and neither inner
/// key showed that pair of surfaces on that pair of pixels, the edge between them is one that
/// neither the keys nor the prediction put there (the tip of a silhouette that sweeps across pixels
/// both keys show behind it): the neighbour is traced too, with the pixels within two of it
/// predicted to show what it shows, and so on until the traced edges close.
///
/// The target is against the converged picture when `settingsMse` is the frame traced at t's
/// own mean squared error against it (SettingsError.h; per channel, levels² of 255): the error
/// left untraced is held to the target's less that, and to no less than a quarter of the
/// target's where the settings leave less (they alone then miss the target, and the estimate
/// says so). With 0 the target is against the frame traced at t. Throws InvalidParameter for a
/// target outside (0, kMaxQualityTargetDb] or NaN, a settings error below 0 or not finite, or a
/// tracer of another size. The tracer traces the pixels as its rendering says: with the adaptive
/// grid each re-traced pixel costs its whole lattice block, so a tracer made for this has its
/// rendering's scatteredPixelRendering(), each pixel its own centre ray (as the filters do).
ASRTINTERPOLATION_EXPORT PathCompletion completePathFrame(
  PathFrame& frame, const FrameTracer& tracer, double targetDb, double probeFraction = 0.01,
  double settingsMse = 0.0, EstimateScaling scaling = EstimateScaling::Ratio);

/// What a PixelTracer returns: the records of the pixels asked for, in the order given, and the
/// rays integrated to make them (0 for records served from a store).
struct TracedPixels
{
  std::vector<RayRecord> records;
  double rays = 0;
};

/// Traces the given pixels (i, j) at the frame's parameters and returns their records and the
/// rays it integrated. With `border` empty each record is the whole frame's record of that pixel
/// (FrameTracer::tracePixels's); else the records read the edge neighbours' samples given there
/// instead of tracing them (FrameTracer::tracePixelsBeside's).
using PixelTracer = std::function<TracedPixels(const std::vector<std::pair<int, int>>& pixels,
                                               const std::vector<JacobianSample>& border)>;

/// The pixel tracer of a frame tracer (which must outlive it): FrameTracer::tracePixelsBeside,
/// and the rays it integrated read around each call (FrameTracer::raysIntegrated; the records'
/// raysPerPixel leave out the edge neighbours it traces and drops). The centre rays it traced are
/// kept between its calls (CentreRays): a pixel or neighbour traced for one list is not traced
/// again for a later one, and the records are the same.
ASRTINTERPOLATION_EXPORT PixelTracer pixelTracerOf(const FrameTracer& tracer);

/// As above, the pixels got from `trace` (called with the must-retrace pixels and the probes,
/// then once per round of neighbours that contradict traced pixels, then with the chosen ones;
/// each list is a function of the frame as predicted and of the records traced before, so the
/// same keys and the same records choose the same lists). Each list is traced beside the edge
/// neighbours the frame vouches for (the `border` of the call): those traced before, and predicted
/// ones whose estimate is within a level a channel. Their rays are not traced only to be dropped;
/// the records' Jacobians and colours read them, within that level of what the traced rays would
/// give. The other neighbours are traced and dropped. A caller may serve the lists from a store
/// of pixels traced before beside the same border, provided they are the traced records.
ASRTINTERPOLATION_EXPORT PathCompletion completePathFrame(
  PathFrame& frame, const PixelTracer& trace, double targetDb, double probeFraction = 0.01,
  double settingsMse = 0.0, EstimateScaling scaling = EstimateScaling::Ratio);

struct SettingsRefinement; // SettingsError.h

/// As above, held to the converged picture through `refinement.settings` (its bound the
/// settingsMse above). Where that bound is above kRefineSettingsAbove of the target's error, which
/// re-tracing with the keys' settings could not make up, the pixels of the strata holding it
/// (strataToRefine, chosen on the frame once its must-retrace pixels and probes are traced, for
/// the fewest rays with the re-tracing the prediction then needs) are traced with
/// `refinement.converged` and carry none of it; the prediction is then held to the target less
/// what the other strata leave. Throws InvalidParameter for a refinement without a tracer.
ASRTINTERPOLATION_EXPORT PathCompletion completePathFrame(
  PathFrame& frame, const PixelTracer& trace, double targetDb, double probeFraction,
  const SettingsRefinement& refinement, EstimateScaling scaling = EstimateScaling::Ratio);
}

#endif
