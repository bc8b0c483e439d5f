// Intermediate frames from two matched frames (the paper's rendering engine, second half): every
// pixel of both frames is a splat that moves on the straight line between its position in A and
// its position in B, its colour blending as (1 − t)·c_A + t·c_B.
//
// A pair of pixels that match each other is drawn once, from the frame nearer in t; every other
// splat is drawn from its own frame, A's weighing (1 − t) and B's t, normalised per output
// pixel. t = 0 and t = 1 are A and B themselves, to the bit. Visibility: the lowest layer wins
// (image order; the shadow and the empty sky lie behind every image), then the shortest path
// length; splats within a margin of the front (relative depthTolerance, plus the splat's own
// path-length slope) blend. Coverage: a splat's footprint is the unit pixel mapped by (1 − s)·I +
// s·D (D the pair's Jacobian, s its side's time), its singular values clamped to [1,
// maxMagnification], with a tent kernel in the splat's own coordinates (bilinear weights when the
// map is the identity, and a partition of unity under any affine map). Pixels no splat reaches are
// filled by push-pull and counted.
//
// Plain C++, OpenMP: the frame is cut into bands of rows, each band rendered by one thread into
// its own accumulators (no atomics, no allocation per pixel); the result does not depend on the
// number of threads. A 1920×1080 frame draws ~2.3 M splats: the per-splat work is kept small by
// what buildSplats precomputes (the bands a splat can reach, and per list entry the s within
// which it reaches that band, so most entries of a band that is not theirs at t are skipped
// unread), four-lane (SSE) colour sums, a branch-light deposit, and bands handed out largest
// first; the splats and their deposit order are those of the straightforward renderer, so the
// frames are the same to the bit.
#ifndef asrt_FrameInterpolation_h
#define asrt_FrameInterpolation_h

#include "FrameMatching.h"
#include "asrtInterpolationModule.h"

#include <array>
#include <cstdint>
#include <vector>

namespace asrt
{
/// Where an output pixel's colour came from.
enum class PixelClass : std::uint8_t
{
  Matched = 0,    ///< dominated by a splat of a matched pair
  OneSided = 1,   ///< by a splat seen in one frame only
  HoleFilled = 2, ///< no splat reached it: filled from its neighbours
  Ambiguous = 3,  ///< by a splat whose partner is ambiguous
  Retraced = 4    ///< traced afresh (exact mode)
};
constexpr int kPixelClassCount = 5;
ASRTINTERPOLATION_EXPORT const char* toString(PixelClass c);

struct InterpolationOptions
{
  /// A splat spreads over at most this many pixels per source pixel along any axis; beyond that
  /// (the photon ring between very different masses) the gaps are holes, filled and counted.
  float maxMagnification = 4.0f;
  /// Surfaces whose path lengths lie within this fraction of each other blend instead of hiding.
  float depthTolerance = 0.02f;
  /// Rows rendered by one thread at a time; 0 (default): height/16, at least 16 (bands then stay
  /// in cache, and a splat's path rarely crosses more than two).
  int bandRows = 0;
};

/// Everything about a pair of frames that does not depend on t: built once, rendered at any t.
struct SplatSet
{
  /// One pixel of one frame. "This" is the pixel's own frame, "other" the other frame; a splat of
  /// A moves with s = t, a splat of B with s = 1 − t, from its pixel towards the other frame.
  struct Splat
  {
    float dx = 0, dy = 0;   ///< displacement from its pixel to its position in the other frame
    float length = 0;       ///< path length in this frame
    float dLength = 0;      ///< path length in the other frame minus this one
    float margin = 0;       ///< path-length margin within which other splats blend with it
    std::int32_t footprint; ///< index into jacobians, −1 when D is near the identity
    std::uint8_t color[3];  ///< in this frame
    std::uint8_t other[3];  ///< at its position in the other frame
    std::uint8_t layer = 0; ///< image order (clamped); kBackdrop for the shadow and empty sky
    std::uint8_t cls = 0;   ///< PixelClass of the pixel it comes from, | kMutual
  };
  static constexpr std::uint8_t kBackdrop = 15;
  /// Flag in Splat::cls: the pixel and its partner match each other (each lands within a pixel
  /// of the other). Such a pair is one scene point seen twice: it is drawn once, from the frame
  /// nearer in t (A's splat for t < ½, B's from ½ on), at full weight.
  static constexpr std::uint8_t kMutual = 0x80;

  int width = 0, height = 0;
  InterpolationOptions options;
  float layerStride = 0;     ///< key = layer · stride + path length
  std::vector<Splat> splats; ///< A's pixels, then B's (index k ≥ width·height: B)
  std::vector<std::array<float, 4>> jacobians; ///< D of the splats that need one
  std::vector<float> jacobianDeviation;        ///< max |D − I| entry, per jacobian
  int bandRows = 16;
  /// The splats band b may need, in four groups g (A's mutual, A's other, B's mutual, B's other,
  /// so that a frame skips the mutual group it does not draw without reading it). A splat whose
  /// rows over the whole of t ∈ [0, 1] touch at most two bands is listed in them once ("static",
  /// segment s = 0); one that travels further is listed, for each of kSegments slices of t, in
  /// the bands it touches during that slice (s = 1 + slice). List (b, s, g) is
  /// bandSplats[bandStart[l], bandStart[l + 1]) with l = (b · (kSegments + 1) + s) · 4 + g.
  static constexpr int kSegments = 16;
  std::vector<std::int64_t> bandStart;
  std::vector<std::int32_t> bandSplats;
  /// Per entry of bandSplats, the s (in 255ths, rounded outwards) within which that splat may
  /// touch that band: entries outside it are skipped without reading the splat.
  std::vector<std::array<std::uint8_t, 2>> bandReach;
  std::size_t listIndex(int band, int segment, int group) const
  {
    return (static_cast<std::size_t>(band) * (kSegments + 1) + static_cast<std::size_t>(segment)) *
             4 +
           static_cast<std::size_t>(group);
  }
  /// The source rays' fields, for the output's per-pixel arrays (index as splats).
  std::vector<std::int32_t> objectId, imageOrder;
  std::vector<std::uint8_t> termination;
  std::vector<double> pathLength; ///< in this frame, exactly
  /// The distance from the hole's centre of the scene point a splat shows, +∞ where its ray hit
  /// no object (the horizon at t hides what lies within it, renderFrame).
  std::vector<float> hitRadius;
  std::size_t pixelCount() const { return static_cast<std::size_t>(width) * height; }
};

/// Builds the splats of both frames from their correspondence. Partner colours and path lengths
/// are sampled bilinearly from the other frame's pixels of the same image around the position.
ASRTINTERPOLATION_EXPORT SplatSet buildSplats(const FrameSamples& a, const FrameSamples& b,
                                              const Correspondence& c,
                                              const InterpolationOptions& options = {});

/// One rendered intermediate frame.
struct InterpolatedFrame
{
  int width = 0, height = 0;
  double t = 0;
  std::vector<std::uint8_t> rgb;      ///< 3 per pixel, row-major from the bottom-left
  std::vector<PixelClass> pixelClass; ///< per pixel
  std::vector<std::int32_t> source;   ///< the front splat at the pixel, −1 for filled holes
  std::int64_t holes = 0;             ///< pixels no splat reached (before filling)
  /// Fraction of pixels in each PixelClass.
  std::array<double, kPixelClassCount> fractions() const;
};

/// Reusable buffers of renderFrame: per-thread band accumulators and the hole-filling pyramid.
struct InterpolationWorkspace
{
  /// One output pixel of a band being rendered: the weighted colour sum and weight, the nearest
  /// key and the visibility limit seen so far, and the nearest splat. Aligned so that no
  /// accumulator straddles two cache lines (a splat's four taps then touch at most four).
  struct alignas(32) Accumulator
  {
    float r, g, b, weight;
    float nearest, limit;
    std::int32_t best;
    std::uint8_t cls, pad[3];
  };
  std::vector<std::vector<Accumulator>> bands;
  bool bandsEmpty = false; ///< every accumulator of `bands` is empty (a render finished)
  std::vector<float> fill, fillWeight, pyramid;
  std::vector<std::int32_t> holes, stillHoles, allHoles;
  std::vector<std::vector<std::int32_t>> bandHoles; ///< each band's holes, in pixel order
  std::vector<int> bandOrder;                       ///< the order bands are handed to threads in
  std::vector<std::int64_t> bandWork;               ///< list entries a band draws at t
  InterpolatedFrame sideA, sideB;                   ///< for renderDisagreement
};

enum class SplatSides
{
  Both,  ///< the interpolated frame
  AOnly, ///< what A's splats alone draw at t, in A's colours
  BOnly  ///< what B's splats alone draw at t, in B's colours
};

/// Renders the frame at t ∈ [0, 1] into `out` (resized as needed). t = 0 (t = 1) with both
/// sides is A (B) itself. `horizonRadius` (> 0: the hole's outer horizon at t): a hole that grows
/// between the frames swallows the parts of the surfaces that reach into it, and the splats of
/// scene points no further than that from its centre are not drawn (the Euclidean distance: in
/// Kerr, whose horizon is an oblate spheroid in the tracer's coordinates, only those certainly
/// inside it). On the mass ramp between M = 0.56 and 0.67 (200×200) the frame midway scores
/// 25.5 dB against the frame traced there, 23.3 dB with those splats drawn.
ASRTINTERPOLATION_EXPORT void renderFrame(const SplatSet& splats, double t, InterpolatedFrame& out,
                                          InterpolationWorkspace& workspace,
                                          SplatSides sides = SplatSides::Both,
                                          double horizonRadius = 0.0);

/// Per pixel, the largest channel difference between the frame as A's splats alone and as B's
/// splats alone draw it at t (255 where only one of them reaches the pixel): where the two frames
/// disagree about the frame at t, interpolation cannot be trusted.
ASRTINTERPOLATION_EXPORT void renderDisagreement(const SplatSet& splats, double t,
                                                 std::vector<std::uint8_t>& out,
                                                 InterpolationWorkspace& workspace);

/// The ray fields behind an output pixel: those of the front splat's source pixel, its path
/// length interpolated to t.
struct SourceFields
{
  std::int32_t objectId = -1, imageOrder = 0, termination = 0;
  double pathLength = 0;
};
ASRTINTERPOLATION_EXPORT SourceFields sourceFields(const SplatSet& splats, std::int32_t splat,
                                                   double t);
/// sourceFields of every pixel of `frame` (rendered from `splats`), into per-pixel arrays of
/// frame.width · frame.height entries each; threads share the pixels (OpenMP).
ASRTINTERPOLATION_EXPORT void sourceFieldsOf(const SplatSet& splats, const InterpolatedFrame& frame,
                                             std::int32_t* objectId, std::int32_t* imageOrder,
                                             std::int32_t* termination, double* pathLength);

/// Fills the pixels of weight 0 from the others by push-pull (Gortler et al., "The Lumigraph",
/// 1996): weighted averages over a pyramid of halvings, then every level's gaps take the bilinear
/// upsampling of the level above. `values` holds `channels` floats per pixel, `weights` one per
/// pixel (> 0: known). Known pixels are left unchanged. Returns false if no pixel is known.
/// `scratch`, if given, holds the pyramid between calls (no allocation once it is large enough).
ASRTINTERPOLATION_EXPORT bool pushPullFill(int width, int height, int channels, float* values,
                                           const float* weights,
                                           std::vector<float>* scratch = nullptr);
}

#endif
