// How far an interpolated frame is from the frame traced at its parameters, and how many of its
// pixels to re-trace for a quality target.
//
// Two parts, kept apart on purpose:
//  - a per-pixel *ranking* estimate from what the stored rays know (estimatePixelErrors): where
//    A's and B's predictions disagree, where the picture has contrast for a misplaced edge to
//    show, and where no matched splat vouches for the pixel. It orders the pixels for
//    re-tracing, worst first; its scale is not trusted.
//  - a *calibration* by probes (chooseRetraceCount): a fixed pseudo-random sample of pixels is
//    traced at t, and the true squared error of those probes that the ranking would leave alone
//    estimates, without bias, the error of all pixels left alone. The re-trace count is the
//    smallest for which that estimate, plus its standard error, meets the target.
// The probes measure what the ranking leaves when it leaves errors spread over many pixels; a
// few heavy pixels that the ranking misses can escape them (a pixel a probe sees stands for about
// 1/fraction pixels). So the ranking must know the heavy errors roughly for the target to hold.
// Measured on the mass ramp of Figs. 4–5 at 200×200 (key frames M = 0.76 and 0.98), this ranking
// does not yet: it needs 2 to 6 times the re-traced pixels of an oracle ranking by the true
// error, and frames that the probes estimate above a target can fall up to 10 dB short of it.
// Plain C++.
#ifndef asrt_ErrorEstimate_h
#define asrt_ErrorEstimate_h

#include "FrameInterpolation.h"
#include "asrtInterpolationModule.h"

#include <cstdint>
#include <vector>

namespace asrt
{
/// The highest quality target accepted, in dB: beyond it only re-tracing every pixel meets it.
constexpr double kMaxQualityTargetDb = 100.0;

/// Per pixel of `frame`, a score that grows with its expected error against the traced frame:
/// (1 + d)^½ (1 + g)², d the disagreement of A's and B's splats there (renderDisagreement), g the
/// largest channel step to an edge neighbour in the interpolated picture (the contrast a
/// misplaced edge shows); hole-filled and ambiguous pixels, which no splat vouches for, rank
/// above all others. The exponents were chosen on the mass ramp of Figs. 4–5 at 200×200 by the
/// re-trace budget they need for 35 and 40 dB; disagreement alone, contrast alone, and products
/// with the splats' motion curvature, Jacobian deviation or magnification did no better.
ASRTINTERPOLATION_EXPORT void estimatePixelErrors(const InterpolatedFrame& frame,
                                                  const std::vector<std::uint8_t>& disagreement,
                                                  std::vector<float>& estimate);

/// The pixels in order of decreasing estimate, ties by pixel index: the order of re-tracing.
ASRTINTERPOLATION_EXPORT std::vector<std::int32_t> retraceOrder(const std::vector<float>& estimate);

/// The probe pixels of a frame of `pixels` pixels: those whose hash (of the pixel index and
/// `seed`) falls in the lowest `fraction`, and at least `minimum` (all if the frame is smaller).
/// Fixed by the arguments alone, in increasing order.
ASRTINTERPOLATION_EXPORT std::vector<std::int32_t> probePixels(std::size_t pixels, double fraction,
                                                               std::size_t minimum,
                                                               std::uint64_t seed);

/// What a quality target asks of one frame.
struct RetraceChoice
{
  std::size_t retrace = 0;    ///< the first `retrace` pixels of the order are to be re-traced
  double estimatedMse = 0;    ///< of the frame so completed, per channel, in levels² of 255
  double estimatedPsnr = 0;   ///< 10 log10(255² / estimatedMse); infinite if no error is left
  double standardError = 0;   ///< of estimatedMse
  std::size_t probesLeft = 0; ///< probes among the pixels left interpolated, which measured it
};

/// Standard errors above the probes' mean at which a re-trace count is judged: the count is the
/// first of many that meets the target, so a single standard error would pick a low fluctuation
/// of the probes' mean more often than not.
constexpr double kProbeConfidence = 2.0;

/// The smallest re-trace count k for which the frame with the first k pixels of `order` and all
/// probes re-traced is estimated, at `confidence` standard errors above the probes' mean, to be
/// within `targetDb` of the traced frame. `probeRank[q]` is the position in `order` of probe q and
/// `probeError2[q]` its true squared error summed over the three channels (levels²). Re-traced
/// pixels are exact: the re-traced subset is the traced frame's pixels, bit for bit. Throws
/// InvalidParameter for a target outside (0, kMaxQualityTargetDb] or NaN.
ASRTINTERPOLATION_EXPORT RetraceChoice chooseRetraceCount(std::size_t pixels,
                                                          const std::vector<std::size_t>& probeRank,
                                                          const std::vector<double>& probeError2,
                                                          double targetDb,
                                                          double confidence = kProbeConfidence);

/// PSNR of a mean squared error per channel (levels² of 255): infinite for 0.
ASRTINTERPOLATION_EXPORT double psnrOfMse(double mse);
/// The mean squared error per channel (levels² of 255) of a PSNR: psnrOfMse's inverse.
ASRTINTERPOLATION_EXPORT double mseOfPsnr(double psnr);
}

#endif
