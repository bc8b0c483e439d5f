// The adaptive ray grid: a frame's centre rays traced on a lattice and refined where the rays
// disagree, the rest interpolated.
//
// The frame is cut into blocks whose corners lie on the lattice of step L (pixels whose
// coordinates are multiples of L; the last blocks of a row or column end at the frame's edge). A
// block traces its 9 points (corners, edge midpoints, centre) and is smooth when they end alike
// (object, image order, termination: a hit, the horizon or the sky) and, on a surface, the
// bilinear map of (u, v) from the 4 corners predicts the 5 other points to within the tolerance
// (u the short way round: du = (a − b) − round(a − b)). A smooth block fills its other pixels
// bilinearly over its 4 sub-quads from all 9 points. A block of at least 8 pixels a side whose
// points end alike on a surface but whose (u, v) bends traces the centres of its 4 quarters too
// (which its quarters would trace first): if the biquadratic through the 9 points predicts them
// to within the tolerance, it fills the block. A block that is neither splits at its midpoints
// into 4, down to blocks of at most 2 pixels a side, whose pixels are all among their 9 points.
// A lattice block whose 9 points all fell into the hole splits once, however alike they end,
// when a point of an edge neighbour's middle row (column) did not: inside the shadow the lens
// thins the images of objects near the horizon below the points' spacing.
//
// A pixel belongs to the block whose half-open range [x0, x1) × [y0, y1) holds it (the frame's
// last column and row belong to the blocks that end there). Its record is the traced ray if the
// processing of its lattice block traced it, else its smooth sub-block's interpolation: a
// function of the rays of its own lattice block and of its edge neighbours' middle rows
// (columns), each ray a function of its pixel. So a frame is the same bit for bit at any thread
// count and in any split into bands, subsets or ranks: a split processes the whole lattice blocks
// holding its pixels, with the rays of their neighbours they look at.
//
// Like any sampling of the picture, features smaller than the spacing of a block's points (an
// object whose image falls between them) can be missed by the block that holds them.
#ifndef asrt_AdaptiveGrid_h
#define asrt_AdaptiveGrid_h

#include "RayRecord.h"
#include "asrtTracingModule.h"

#include <array>
#include <utility>
#include <vector>

namespace asrt
{
/// The largest lattice step a frame's grid may take.
constexpr int kMaxGridLattice = 256;

/// A block of the grid: the pixels with x0 ≤ i ≤ x1, y0 ≤ j ≤ y1 (its corners).
struct GridBlock
{
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
  int xm() const { return x0 + (x1 - x0) / 2; }
  int ym() const { return y0 + (y1 - y0) / 2; }
  bool operator==(const GridBlock& o) const
  {
    return x0 == o.x0 && y0 == o.y0 && x1 == o.x1 && y1 == o.y1;
  }
};

/// The lattice block of a width × height frame whose half-open range holds pixel (i, j).
ASRTTRACING_EXPORT GridBlock latticeBlock(int i, int j, int lattice, int width, int height);

/// Whether pixel (i, j) belongs to the block: in [x0, x1) × [y0, y1), or on its far edge where
/// that is the frame's last column (row).
ASRTTRACING_EXPORT bool ownsPixel(const GridBlock& b, int i, int j, int width, int height);

/// The 9 points of a block in the order (x0, y0), (xm, y0), (x1, y0), (x0, ym), ..., (x1, y1):
/// index 3 b + a for column a and row b of {x0, xm, x1} × {y0, ym, y1}.
ASRTTRACING_EXPORT std::array<std::pair<int, int>, 9> blockPoints(const GridBlock& b);

/// Whether a block with these 9 point records (blockPoints' order) is smooth at this tolerance.
ASRTTRACING_EXPORT bool blockIsSmooth(const GridBlock& b, const std::array<const RayRecord*, 9>& p,
                                      double tolerance);

/// The interpolated record of pixel (i, j) of a smooth block from its 9 point records:
/// objectId, imageOrder and termination from the block; u, v, hitPoint, hitNormal (renormalised),
/// affineLength and winding bilinear over the sub-quad holding the pixel (u unwrapped from the
/// sub-quad's first corner, the short way); chordError and maxAbsH the largest of the sub-quad's
/// corners' (the rays it comes from); steps 0 (no ray was traced); origin the eye; direction and
/// momentum those of the pixel's own ray (exact: `direction`, `momentum`); the Jacobian
/// ∂(u, v)/∂(i, j) that of the bilinear map; the colour unset (the caller shades); traced false
/// and raysPerPixel 0 until anti-aliasing counts it.
ASRTTRACING_EXPORT RayRecord interpolateRecord(const GridBlock& b,
                                               const std::array<const RayRecord*, 9>& p, int i,
                                               int j);

/// Whether the 9 point records end alike (object, image order, termination) and the way they end
/// may be interpolated (a hit, the sky or the horizon; not a ray the integrator lost).
ASRTTRACING_EXPORT bool blockEndsAlike(const std::array<const RayRecord*, 9>& p);

/// Whether a block is large enough (at least 8 pixels a side) to try the biquadratic through its
/// 9 points where the bilinear map of its corners does not fit. Smaller blocks split down to
/// their pixels instead: taken at 4 pixels a side, the biquadratic let a rod thinner than a pixel
/// slip between its points (ThinObjectsBesideTheHoleKeepEveryPixel).
ASRTTRACING_EXPORT bool admitsQuadratic(const GridBlock& b);

/// The centres of the block's 4 quarters (the blocks it would split into), in blockPoints' order
/// of the quarters: where the biquadratic is checked.
ASRTTRACING_EXPORT std::array<std::pair<int, int>, 4> quarterCentres(const GridBlock& b);

/// Whether the biquadratic (u, v) through the 9 point records (u unwrapped from the first, the
/// short way) predicts the 4 quarter-centre records `q` to within the tolerance, all ending as
/// the points do.
ASRTTRACING_EXPORT bool quadraticFits(const GridBlock& b, const std::array<const RayRecord*, 9>& p,
                                      const std::array<const RayRecord*, 4>& q, double tolerance);

/// The interpolated record of pixel (i, j) from the biquadratic through the block's 9 point
/// records: the fields interpolateRecord interpolates, over the whole block instead of a
/// sub-quad; chordError and maxAbsH the largest of the 9; the Jacobian that of the biquadratic.
ASRTTRACING_EXPORT RayRecord interpolateRecordQuadratic(const GridBlock& b,
                                                        const std::array<const RayRecord*, 9>& p,
                                                        int i, int j);

/// The lattice blocks holding the given pixels, each once, in a fixed order (by row, then column).
ASRTTRACING_EXPORT std::vector<GridBlock> latticeBlocksOf(
  const std::vector<std::pair<int, int>>& pixels, int lattice, int width, int height);
}

#endif
