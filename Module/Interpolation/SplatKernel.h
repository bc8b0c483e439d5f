// The splat kernel, shared by buildSplats (which lists each splat in the bands of rows it can
// reach) and renderFrame (which draws the splats): which splats are drawn bilinearly, how far a
// splat reaches, and its weights. Private to ASRT::Interpolation.
#ifndef asrt_SplatKernel_h
#define asrt_SplatKernel_h

#include <algorithm>
#include <cmath>

namespace asrt
{
/// Splats whose footprint deviates from the identity by at most this (any entry of s·(D − I))
/// are drawn with plain bilinear weights: neighbours then lie at most 1.25 px apart, which the
/// bilinear kernels (support ±1 px) still cover without gaps.
constexpr float kBilinearDeviation = 0.25f;

// How far from its centre a splat can touch pixels, in pixels (its reach). A bilinear splat's
// four taps lie within a pixel of it. A footprint's map has its singular values clamped to
// [1, maxMagnification] (clampedFootprint), so the image of the kernel's support [−1, 1]² lies
// within √2 · maxMagnification of the centre along either axis (the corner (±1, ±1) is √2 away,
// and no vector is stretched by more than maxMagnification). What rests on that bound decides
// its margin; the two margins, side by side:
/// Listing a splat in the bands its path can reach (buildSplats): the bound as it is. The listing
/// works at the grain of whole bands, and the s within which an entry is drawn adds
/// kBandReachSpare on top. (Changing it would change the listing, and so possibly the frames.)
constexpr float kListingReachMargin = 1.0f;
/// The renderer's test for skipping a listed splat whose footprint cannot touch the band, made
/// before the footprint is computed: a ten-thousandth more, because it compares the centre ±
/// reach with the band's edges directly while the half-extents drawn with are computed in floats
/// and may round a hair above the bound. A skip must never drop a splat that would touch.
constexpr float kDrawReachMargin = 1.0001f;
/// A bilinear splat's reach.
constexpr float kBilinearReach = 1.0f;
/// The s within which a listed splat may touch its band is found for rows widened by the splat's
/// reach and this many pixels more: that s is computed in floats and rounded to 255ths, while the
/// renderer places the splat by its own rounding of y + s·dy. Too wide only costs entries that
/// are skipped after reading; too narrow would lose touches.
constexpr float kBandReachSpare = 1.0f;

/// The reach of a footprint splat, with a margin (kListingReachMargin or kDrawReachMargin).
inline float footprintReach(float maxMagnification, float margin)
{
  return margin * std::sqrt(2.0f) * maxMagnification;
}

/// The splat kernel: a tent in the splat's own coordinates (u, v), (1 − |u|)(1 − |v|) within
/// [−1, 1]², 0 outside. Under any affine footprint the tents of a grid sum to one (a partition of
/// unity), so neighbouring splats leave no gaps and no seams. At the identity map it is bilinear
/// weighting, which bilinearWeights computes from the centre's offset in its cell.
inline float splatWeight(float u, float v)
{
  return std::max(0.0f, 1.0f - std::abs(u)) * std::max(0.0f, 1.0f - std::abs(v));
}

/// The kernel's weights at the four pixels around a centre (ax, ay) into its cell, ax, ay ∈
/// [0, 1): at (0, 0), (1, 0), (0, 1), (1, 1) from the cell's corner.
inline void bilinearWeights(float ax, float ay, float& w00, float& w10, float& w01, float& w11)
{
  w00 = (1 - ax) * (1 - ay);
  w10 = ax * (1 - ay);
  w01 = (1 - ax) * ay;
  w11 = ax * ay;
}
}

#endif
