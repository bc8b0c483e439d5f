// How a frame's pixels get their colours from more than one point of the scene: the options of the
// scene's "rendering" section (AntialiasOptions) and the pass that applies them to traced records.
//
// A pixel is the square of side 1 about its centre ray (Camera::localDirection's convention, pixel
// (i, j) at screen position (i, j)), and its colour is the box-filtered average of the picture
// over that square:
//  - `filter`: the centre ray's texture lookup is averaged over the pixel's footprint on the
//    surface, the parallelogram spanned by the record's Jacobian ∂(u, v)/∂(i, j) (Texture's
//    sampleFootprint). Where the Jacobian is undefined the texture is point-sampled.
//  - `adaptive`: `filter`, and a pixel is sampled by n × n rays (n = adaptivePatternSide) where its
//    footprint is undefined or far from linear (a neighbour's centre ray half a pixel or more from
//    where the footprint puts it), or a colour differs by more than colorThreshold from an edge
//    neighbour's, or where an edge neighbour's centre ray ends differently (object, image order,
//    termination) and the ray through the midpoint between the two centres ends unlike the
//    pixel's own: the edge then crosses into this pixel's half. The n² rays lie on the grid
//    rotated by atan(1/n), one in each of its n × n cells and in each of its n² rows and
//    columns ("n-rooks"); for odd n the centre ray is one of them; each is
//    filtered over its share of the footprint and they are averaged (a box reconstruction;
//    FrameAntialiasing.cxx). A pixel sampled only because its footprint bends (odd n) is first
//    seen through its local quadratic map of (u, v), through its centre ray, its 4 edge
//    neighbours' and the pattern's first corner: where the opposite corner lands within
//    kQuadraticMisfit of a cell's footprint of where the map puts it, in the colour the map
//    predicts, the map places the pattern's other samples. Else it takes the pattern's 4 corner
//    cells (and its centre sample): where those end as the centre ray does and their colours
//    spread by at most kSettledColorSpread, their mean is its colour and the rest of the
//    pattern is not traced (a bend shows only where the texture changes across the pixel). A
//    pixel's raysPerPixel counts its samples and the midpoint rays counted to it (those on its
//    right and upper edges): at most maxRaysPerPixel + 2.
//  - `supersample` N > 1 samples every pixel by the same N × N pattern (for references); with
//    `none`, the samples are point-sampled.
// Every sample position is fixed by the pixel alone, so that a frame is the same bit for bit at
// any thread count and in any split into pieces.
#ifndef asrt_Antialiasing_h
#define asrt_Antialiasing_h

#include "asrtTracingModule.h"

#include <string>

namespace asrt
{
enum class AntialiasMode
{
  None,    ///< one ray at each pixel's centre, point-sampled textures
  Filter,  ///< one ray a pixel, textures filtered over the pixel's footprint
  Adaptive ///< Filter, and extra rays where neighbouring rays disagree
};

ASRTTRACING_EXPORT const char* toString(AntialiasMode m);
/// "none", "filter" or "adaptive"; throws InvalidParameter naming the accepted values otherwise.
ASRTTRACING_EXPORT AntialiasMode antialiasModeFromString(const std::string& s);

/// The largest number of rays a pixel may take (a supersample of 32 × 32).
constexpr int kMaxRaysPerPixel = 1024;

/// The largest spread of any channel (in [0, 1]: three levels of the 8-bit picture) among the
/// corner samples of a pixel whose footprint bends that lets them settle its colour.
constexpr double kSettledColorSpread = 3.0 / 255.0;

/// The relative tolerance (where the frame's is tighter) of the rays an adaptively sampled pixel
/// adds to its centre ray. A sample adds only colour: the frame keeps the centre ray's record, and
/// the rays that decide where to sample are traced as it is. On Fig. 1, strongly lensed, samples
/// at 1e-6 land within a thousandth of a pixel of rays traced at 1e-12 (99 %), and within a few
/// hundredths where the map nearly folds (TestAntialiasing); the planar orbit's segments may be
/// three times as long, and the picture against a converged one does not change.
constexpr double kSampleRelativeTolerance = 1e-6;

/// The scene file's "rendering" section.
struct AntialiasOptions
{
  /// The defaults are the "balanced" preset's: of the settings measured in bench/REPORT.md, the
  /// cheapest that reaches 38 dB against a converged picture on every scene there.
  AntialiasMode mode = AntialiasMode::Adaptive;
  /// The most rays an adaptively sampled pixel takes inside itself (centre ray included), 1 to
  /// kMaxRaysPerPixel; the pattern is adaptivePatternSide(maxRaysPerPixel) on a side. The rays
  /// through the midpoints of its edges that decide whether it is sampled come on top (at most
  /// two).
  int maxRaysPerPixel = 9;
  /// N × N rays in every pixel, 1 to 32 (1: only what `mode` adds).
  int supersample = 1;
  /// Largest difference of any channel between neighbouring centre colours (point-sampled, in
  /// [0, 1]) that adaptive sampling leaves alone; above it the pixel is sampled. At 1 (the
  /// default) colour never decides: texture detail within an object is the filter's to average,
  /// and a lower threshold spends rays on it (bench/REPORT.md measures the trade).
  double colorThreshold = 1.0;
  /// The adaptive ray grid (AdaptiveGrid.h): the step of its lattice, 1 to kMaxGridLattice; at 1
  /// every pixel's centre ray is traced. The default, 8 at tolerance 3e-4, is the cheapest
  /// setting measured (bench/REPORT.md, "The adaptive ray grid") whose frames stay within 40 dB
  /// of the full trace and within 0.2 dB of its score against a converged picture, with no
  /// pixel changing object off an edge, on every scene at 200×200, 800×450 and 1920×1080 (16
  /// loses thin higher-order images of Fig. 5's cylinders at 1920×1080).
  int gridLattice = 8;
  /// The largest error of the bilinear (u, v) at a block's check points that leaves it whole.
  double gridTolerance = 3e-4;

  bool operator==(const AntialiasOptions& o) const
  {
    return mode == o.mode && maxRaysPerPixel == o.maxRaysPerPixel && supersample == o.supersample &&
           colorThreshold == o.colorThreshold && gridLattice == o.gridLattice &&
           (gridLattice <= 1 || gridTolerance == o.gridTolerance);
  }
  bool operator!=(const AntialiasOptions& o) const { return !(*this == o); }
};

/// The lattice a frame is traced on: the options' gridLattice, but 1 with a supersample, whose
/// N × N rays in every pixel leave nothing for the grid to save (and would take its
/// interpolated centre as a sample).
inline int effectiveGridLattice(const AntialiasOptions& o)
{
  return o.supersample > 1 ? 1 : o.gridLattice;
}

/// The side of the converged rendering's pattern.
constexpr int kConvergedSide = 4;
/// The rendering of a view's converged picture, the one quality is measured against: every
/// pixel's centre ray traced, and side × side samples on the rotated grid in every pixel, each
/// filtered over its share of the footprint and traced as tightly as the centre rays.
inline AntialiasOptions convergedRendering(int side = kConvergedSide)
{
  AntialiasOptions o;
  o.mode = AntialiasMode::Filter;
  o.supersample = side;
  o.gridLattice = 1;
  return o;
}

/// The side of the converged rendering that judges a quality target of `targetDb` (PSNR): one
/// whose pictures' own error lies at least 6 dB below the target's, so that it adds at most a
/// quarter to the error it measures. Against 16 × 16 samples (Figs. 1 and 5 and the Kerr disk at
/// 200 × 200, every centre ray traced, bench/REPORT.md) 4 × 4 lies 42.8–48.5 dB and 8 × 8
/// 51.0–57.2 dB: each doubling of the side gains about 8 dB. So 4 × 4 judges targets up to 36 dB,
/// 8 × 8 up to 45, 16 × 16 up to 53, and 32 × 32, the most a rendering may take, those above. A
/// frame of more pixels has fewer of them on edges, where that error lies, and fares better. The
/// benches score against it; the settings' own error is estimated against 4 × 4 whatever the
/// target (SettingsError.h, Reference).
inline int convergedSideFor(double targetDb)
{
  if (!(targetDb > 36.0))
    return kConvergedSide;
  if (targetDb <= 45.0)
    return 2 * kConvergedSide;
  return targetDb <= 53.0 ? 4 * kConvergedSide : 8 * kConvergedSide;
}

/// Whether a rendering is converged already: as many samples in every pixel as the converged
/// rendering or more (its frames are their own converged pictures).
inline bool isConvergedRendering(const AntialiasOptions& o)
{
  return o.supersample >= kConvergedSide;
}

/// The rendering for tracing scattered pixels, such as the pixels an interpolated frame re-traces:
/// each its own centre ray, where the adaptive grid would process the whole lattice block around
/// each of them.
inline AntialiasOptions scatteredPixelRendering(AntialiasOptions o)
{
  o.gridLattice = 1;
  return o;
}

/// The options of a frame traced one ray a pixel with point-sampled textures: what a scene text
/// without a "rendering" section was traced with before anti-aliasing existed. Every field is set
/// here, not taken from the defaults: the store writes this section into such texts (schema
/// version 5), and stored frames must keep being found if the defaults change.
inline AntialiasOptions singleRayRendering()
{
  AntialiasOptions o;
  o.mode = AntialiasMode::None;
  o.maxRaysPerPixel = 1;
  o.supersample = 1;
  o.colorThreshold = 1.0;
  o.gridLattice = 1;
  return o;
}

/// The anti-aliasing of the speed/accuracy presets ("fast", "balanced", "accurate"; the
/// integrator's are integratorPreset's), chosen by measurement in bench/REPORT.md: the best quality
/// for its cost. "fast" and "balanced" trace on the default adaptive grid; "accurate" traces every
/// pixel's centre ray, so that no feature narrower than the grid's ray spacing can be missed.
/// Throws InvalidParameter for any other name.
ASRTTRACING_EXPORT AntialiasOptions renderingPreset(const std::string& name);

/// The rays a pixel sampled by the n × n pattern takes: n² for odd n, whose middle sample is the
/// centre ray; n² + 1 for even n, whose pattern cannot hold the centre and stay symmetric (the
/// centre ray is traced for the record and not averaged in). 1 for n = 1.
inline int patternRays(int n)
{
  return n <= 1 ? 1 : n * n + (n % 2 == 0 ? 1 : 0);
}

/// The side of the pattern adaptive sampling uses under a cap: the largest n whose patternRays
/// fit in it (cap 9 gives 3 × 3, cap 16 gives 3 × 3, cap 17 gives 4 × 4).
inline int adaptivePatternSide(int maxRaysPerPixel)
{
  int n = 1;
  while (n < 32 && patternRays(n + 1) <= maxRaysPerPixel)
    ++n;
  return n;
}

/// The side of the converged rendering that a rendering's own error is measured against
/// (SettingsError.h): kConvergedSide, but twice it where the rendering's adaptive pattern has
/// that side. Its sampled pixels would then take the converged picture's own samples (the same
/// rotated grid, each filtered over its cell), and their error would vanish from the measure: at
/// 17 rays a pixel the mass ramp's frames score 43.8 dB mean against 4 × 4, 42.1 against 8 × 8,
/// where the accurate preset scores 41.6 and 43.0.
inline int settingsReferenceSide(const AntialiasOptions& o)
{
  const bool sharesPattern = o.mode == AntialiasMode::Adaptive && o.supersample <= 1 &&
                             adaptivePatternSide(o.maxRaysPerPixel) == kConvergedSide;
  return sharesPattern ? 2 * kConvergedSide : kConvergedSide;
}

/// Throws InvalidParameter naming the field ("rendering.maxRaysPerPixel: ...") unless the cap
/// lies in [1, kMaxRaysPerPixel], the supersample in [1, 32], the threshold in [0, 1], and a frame
/// of `pixels` pixels supersampled N × N stays within kMaxFramePixels rays.
ASRTTRACING_EXPORT void validateRendering(const AntialiasOptions& o, long long pixels);
}

#endif
