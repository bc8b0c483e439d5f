// The error a frame's rendering settings leave against the converged picture of the same view
// (the picture its pixels converge to as they are sampled ever more densely; convergedRendering),
// measured on a few probe pixels traced with the converged rendering. A quality target is a
// promise against the converged picture: an interpolated frame completed to the frame traced at
// its parameter carries that frame's own error too, and a target above what the settings reach
// cannot be met by re-tracing with them.
//
//  - Strata. The error lies mostly where the frame sampled a pixel by more than its centre ray
//    (an edge: the samples approximate the pixel's box average), and on the edges it did not
//    sample (a pixel whose edge neighbour ends otherwise: another object, image or ending), less
//    where the adaptive grid interpolated the centre ray, least where one traced ray's footprint
//    filter did. Each of the four is probed apart (its pixels with the lowest hashes), and the
//    frame's error is their means weighted by their shares of the frame: unbiased, with far less
//    variance than one uniform sample of as many probes, since the rare large errors sit in the
//    smallest strata. Without the edge stratum a rendering that samples no pixel (the fast
//    preset's) was estimated anywhere from 27.5 to 51.5 dB (10th to 90th percentile of 400 draws
//    of the probes) on the Kerr disk, where it scores 32.9 dB: its unsampled edges, 7 % of the
//    pixels, hold 97 % of its error. With it, 30.9 to 36.1 dB, for as many probes (the single
//    rays off the edges, which hold little, probed half as densely).
//  - Bound. The estimate raised by two of its standard errors (the strata's sample variances
//    over their probe counts, weighted by their squared shares).
//  - Pooling. A frame between two keys is traced with their settings on a view between theirs:
//    its error is estimated from both keys' probes together (each stratum's share the keys'
//    mean), which halves the variance of either alone.
//  - Reference. The converged rendering's 4 × 4 filtered samples lie 42–48 dB from 8 × 8
//    filtered or 16 × 16 point samples (Figs. 1 and 4 and the Kerr disk at 200 × 200, every
//    centre ray traced), and their own errors add to the settings' rather than cancel them: a
//    frame of the default settings scores 0.2–1 dB lower against them than against the denser
//    pictures. The estimate errs on the safe side, and stays against 4 × 4 for every target,
//    though above 36 dB a target is judged against 8 × 8 (convergedSideFor): the errors are
//    heavy-tailed (on Fig. 1's orbit with the accurate preset, pixels off by more than 600
//    levels², 0.1 % of the frame, hold a fifth to a quarter of its error), so 80 probes a key
//    mostly miss them and then underestimate, and 4 × 4's own error is the margin that covers
//    it. At --quality 40 on that orbit, 31 frames against 8 × 8: probes against 4 × 4, every
//    frame 39.7 dB or more; against 8 × 8, one frame 38.4 dB, its keys' bound 43 dB where they
//    score 41. A rendering whose adaptive pattern is 4 × 4 (17 rays a pixel) is measured
//    against 8 × 8 instead (settingsReferenceSide): against 4 × 4 its sampled pixels would be
//    the reference's own samples.
//  - Units. Mean squared error per channel in levels² of 255, as psnrOfMse takes it.
#ifndef asrt_SettingsError_h
#define asrt_SettingsError_h

#include "Antialiasing.h"
#include "PathInterpolation.h"
#include "RayRecord.h"
#include "asrtInterpolationModule.h"

#include <cstddef>
#include <cstdint>
#include <vector>

namespace asrt
{
class FrameTracer;
/// Probes drawn in each stratum of a frame (all of it where a stratum is smaller); the sampled
/// pixels, which hold most of the error and its rare large values, get twice as many, the grid's
/// and the traced single rays off the edges, which hold little, half as many: 80 a frame, as
/// many as before the unsampled edges were a stratum of their own.
constexpr std::size_t kSettingsProbesPerStratum = 20;
/// The hash seed of the probes a movie or a filter draws: the same frame, the same probes.
constexpr std::uint64_t kSettingsProbeSeed = 0x5851f42d4c957f2dULL;

/// The strata of a frame's pixels: sampled by more than the centre ray; centre interpolated by
/// the adaptive grid; one traced ray; an edge not sampled (one ray, traced or interpolated, whose
/// edge neighbour in the frame ends otherwise: object, image order or termination).
constexpr int kSettingsStrata = 4;

/// One stratum's probes: its share of the frame's pixels, and the sums of its probes' squared
/// errors per channel.
struct SettingsStratum
{
  double share = 0;
  double count = 0, sum = 0, sum2 = 0;
  double pixels = 0; ///< of the frame (the keys' mean when pooled): a stratum probed whole is exact
};

/// The settings' strata a frame traces with the converged rendering: those of `whole` (bit s:
/// stratum s) entirely, and of stratum `partial` (−1: none) the share `fraction` of its pixels.
struct RefinedStrata
{
  unsigned whole = 0;
  int partial = -1;
  double fraction = 0;
};

/// A frame's error against its converged picture, estimated from probes.
struct SettingsError
{
  SettingsStratum strata[kSettingsStrata];
  double rays = 0; ///< rays integrated to trace the probes with the converged rendering
  /// The estimate: the strata's probe means weighted by their shares (0 with no pixel).
  double mse() const;
  /// The estimate raised by two standard errors; infinite where a stratum with pixels has no
  /// probe.
  double mseBound() const;
  std::size_t probes() const;
  /// The bound's PSNR: what the settings are held to reach against the converged picture.
  double psnr() const;
  /// The bound of what the strata leave where those in `refined` are traced with the converged
  /// rendering, which leaves their pixels none of the error: a stratum traced whole counts
  /// nothing, one traced in part (its pixels drawn by hash, independently of its probes) counts
  /// the part left, 1 − fraction of its mean and of its standard error.
  double mseBoundWithout(const RefinedStrata& refined) const;
};

/// The stratum of each of a whole frame's records (row-major, one per pixel, as its pixels'
/// coordinates say): 0 sampled by more than the centre ray; 1 centre interpolated by the grid;
/// 2 one traced ray; 3 an edge not sampled.
ASRTINTERPOLATION_EXPORT std::vector<std::uint8_t> settingsStrata(
  const std::vector<RayRecord>& frame);

/// The probes of a whole frame's records (row-major, one per pixel): per stratum
/// (settingsStrata), `perStratum` of its pixels (twice as many sampled ones, half as many
/// single rays off the edges), those whose indices hash lowest under `seed`, in increasing order.
ASRTINTERPOLATION_EXPORT std::vector<std::int32_t> settingsProbes(
  const std::vector<RayRecord>& frame, std::size_t perStratum = kSettingsProbesPerStratum,
  std::uint64_t seed = kSettingsProbeSeed);

/// The estimate from the frame's records and the converged records of the probes (in the
/// probes' order). Throws InvalidParameter when the counts differ.
ASRTINTERPOLATION_EXPORT SettingsError settingsError(const std::vector<RayRecord>& frame,
                                                     const std::vector<std::int32_t>& probes,
                                                     const std::vector<RayRecord>& converged);
/// As above, the records at the probes given apart (`probed`, in the probes' order), the strata
/// `frame`'s: the same frame at another adaptive cap (FrameTracer::antialiasAgain), which samples
/// the same pixels and so has the same strata, measured without making it whole.
ASRTINTERPOLATION_EXPORT SettingsError settingsError(const std::vector<RayRecord>& frame,
                                                     const std::vector<std::int32_t>& probes,
                                                     const std::vector<RayRecord>& probed,
                                                     const std::vector<RayRecord>& converged);

/// The probes of `frame` (width × height records) traced by `converged` (the frame's scene with
/// a converged rendering), and the estimate. Throws InvalidParameter for a frame of another
/// size than width × height.
ASRTINTERPOLATION_EXPORT SettingsError measureSettingsError(
  const std::vector<RayRecord>& frame, int width, int height, const PixelTracer& converged,
  std::size_t perStratum = kSettingsProbesPerStratum);

/// Two keys' probes together (Pooling above): the estimate for a frame between them.
ASRTINTERPOLATION_EXPORT SettingsError pooled(const SettingsError& a, const SettingsError& b);

/// Raising the rendering where the settings fall short. A target above what the keys' settings
/// reach cannot be met by re-tracing with them, but the settings' error lies in a few strata (the
/// sampled edges: a tenth of the pixels, most of the error): those pixels traced with the
/// converged rendering that judges the target carry none of it, and the frame can then reach the
/// target. Where the settings' bound is above kRefineSettingsAbove of the target's error,
/// completePathFrame traces strata so, worst probe mean first (the most error removed for each
/// pixel traced, every pixel costing that rendering's rays), the last in part (strataToRefine),
/// for the share of the target's error left to the settings that costs the fewest rays with the
/// re-tracing the prediction then needs.
struct SettingsRefinement
{
  SettingsError settings; ///< the keys' error (pooled), by stratum
  /// The frame at t traced with the converged rendering that judges the target
  /// (convergedRendering(convergedSideFor(target))); its lists are given the border the keys'
  /// settings' lists are (completePathFrame).
  PixelTracer converged;
  /// The rays it takes a pixel, by which completePathFrame weighs refining against re-tracing:
  /// that rendering's n × n samples.
  double raysPerPixel = static_cast<double>(kConvergedSide) * kConvergedSide;
};

/// The refinement of a frame with the keys' `settings`, traced by `converged` (the frame at t with
/// the rendering that judges the target, convergedRendering(convergedSideFor(target)); it must
/// outlive the result), whose rays a pixel are that rendering's samples.
ASRTINTERPOLATION_EXPORT SettingsRefinement refinementFor(const SettingsError& settings,
                                                          const FrameTracer& converged);
/// Where the settings' bound exceeds this share of the target's error, strata are re-traced
/// converged: above it the prediction would be held to less than a quarter of the target.
constexpr double kRefineSettingsAbove = 0.75;

/// Whether a frame with the keys' `settings` needs their error's strata refined to reach
/// `targetDb`: their bound is above kRefineSettingsAbove of the target's error (completePathFrame
/// refines then; a caller may skip making the converged tracer otherwise).
ASRTINTERPOLATION_EXPORT bool settingsFallShort(const SettingsError& settings, double targetDb);

/// The strata to trace with the converged rendering for the settings' bound to fall to
/// `allowedMse` or below: none where it is there already, else the strata by their probes' mean
/// error, worst first (a stratum with pixels and no probe first of all, its error unknown), as
/// many whole as it takes, the last of them only in the share it takes (to a thousandth, rounded
/// up; whole where its error is unknown).
ASRTINTERPOLATION_EXPORT RefinedStrata strataToRefine(const SettingsError& e, double allowedMse);

/// The pixels (row-major indices) of a whole frame's records in the strata `refined` traces
/// (settingsStrata): all of its whole strata, and of its partial one the share whose indices
/// hash lowest (probePixels). In increasing order.
ASRTINTERPOLATION_EXPORT std::vector<std::int32_t> pixelsOfStrata(
  const std::vector<RayRecord>& frame, const RefinedStrata& refined);
/// As above, of a frame whose strata (settingsStrata) are given.
ASRTINTERPOLATION_EXPORT std::vector<std::int32_t> pixelsOfStrata(
  const std::vector<std::uint8_t>& strata, const RefinedStrata& refined);
}

#endif
