// Textures: the colour of a surface at its coordinates (u, v), point-sampled or averaged (a box
// filter) over the footprint of a pixel on the surface. Plain C++ on Eigen; images arrive as pixel
// buffers.
#ifndef asrt_Texture_h
#define asrt_Texture_h

#include "AsrtTypes.h"
#include "asrtTracingModule.h"

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace asrt
{
/// Colour, RGB, each channel in [0, 1]. Image textures give their 8-bit values / 255 unchanged (no
/// gamma conversion), so that a flat-space render reproduces an image's pixels.
using Color = Vec3;

/// The footprint of a pixel (or of one cell of a pixel) on a surface: how (u, v) change across it
/// along the screen's two axes. It is the parallelogram (u, v) + s·(dudx, dvdx) + t·(dudy, dvdy),
/// s, t ∈ [−½, ½].
struct TextureFootprint
{
  double dudx = 0, dvdx = 0, dudy = 0, dvdy = 0;
};

/// True if every entry of the footprint is finite.
inline bool isFinite(const TextureFootprint& f)
{
  return std::isfinite(f.dudx) && std::isfinite(f.dvdx) && std::isfinite(f.dudy) &&
         std::isfinite(f.dvdy);
}

/// What every texture is: thread-safe and allocation-free to sample.
class ASRTTRACING_EXPORT Texture
{
public:
  virtual ~Texture() = default;
  /// Colour at surface coordinates (u, v) ∈ [0, 1]².
  virtual Color sample(double u, double v) const = 0;
  /// The average of the texture over the footprint about (u, v) (a box filter over the pixel). A
  /// footprint with a non-finite entry falls back to sample(u, v). Default implementation:
  /// sample(u, v).
  virtual Color sampleFootprint(double u, double v, const TextureFootprint& f) const;
};

class ASRTTRACING_EXPORT SolidTexture final : public Texture
{
public:
  /// Throws InvalidParameter unless every channel lies in [0, 1].
  explicit SolidTexture(const Color& c);
  Color sample(double, double) const override { return this->C; }
  Color sampleFootprint(double, double, const TextureFootprint&) const override { return this->C; }

private:
  Color C;
};

/// nu × nv checks of two colours: `a` on the check containing (0, 0) and wherever
/// floor(u·nu) + floor(v·nv) is even, `b` elsewhere. Periodic in u and v.
///
/// The checker is (a + b)/2 + (a − b)/2 · g(u)·h(v), g(u) = ±1 the parity of the check column
/// floor(frac(u)·nu) (h likewise in v). Its footprint average is exact, computed by Green's
/// theorem: ∬ g h dA = ∮ G(u) h(v) dv, G the primitive of g (piecewise linear: a triangle wave,
/// plus a ramp of 1/nu a period for odd nu, whose checks do not alternate across u = 0). Along
/// each side of the parallelogram G is linear and h constant between the crossings of check
/// lines, so the midpoint rule is exact piece by piece. A footprint whose sides cross more than
/// kMaxExactCrossings check lines uses the axis-aligned box with the parallelogram's marginal
/// variances instead (widths √(dudx² + dudy²), √(dvdx² + dvdy²)), separable and exact for an
/// axis-aligned footprint; a footprint that large (its sides spanning 256 checks together) averages
/// near the texture's mean either way, but for thin ones along a diagonal of the checks. Both give
/// sample(u, v) for a footprint inside one check, and the texture's mean for a huge one
/// ((a + b)/2 for even nu or nv). The cost grows with the number of lines crossed.
class ASRTTRACING_EXPORT CheckerTexture final : public Texture
{
public:
  /// Above this many check-line crossings of the footprint's outline, the box approximation.
  static constexpr int kMaxExactCrossings = 512;

  /// Throws InvalidParameter unless nu, nv ≥ 1 and the colours lie in [0, 1].
  CheckerTexture(int nu, int nv, const Color& a, const Color& b);
  Color sample(double u, double v) const override;
  /// Exact below kMaxExactCrossings crossings, the variance-matched box above.
  Color sampleFootprint(double u, double v, const TextureFootprint& f) const override;
  /// The variance-matched axis-aligned box alone, whatever the footprint (exact if it is
  /// axis-aligned): the approximation sampleFootprint falls back to.
  Color sampleBox(double u, double v, const TextureFootprint& f) const;

private:
  Color mix(double gh) const { return 0.5 * (this->A + this->B) + 0.5 * gh * (this->A - this->B); }
  int Nu, Nv;
  Color A, B;
};

/// An RGB image, 8 bits a channel, row-major, row 0 at v = 0 (the bottom row, as VTK's readers
/// store it); pixel (i, j) is centred at ((i + ½)/W, (j + ½)/H). Sampled bilinearly between pixel
/// centres, periodic in u and clamped in v (the equirectangular convention of a sky).
///
/// Footprints are averaged on a mip pyramid built in the constructor: level k + 1 has
/// max(1, ⌊w/2⌋) × max(1, ⌊h/2⌋) texels, each the exact area average of the level-k texels it
/// covers (a 2 × 2 box for even sizes; for an odd size a coarse texel covers 2 + 1/⌊w/2⌋ fine
/// ones, partly), so that every level partitions [0, 1]² as level 0 does, keeps the image's
/// registration and mean, and needs no wrap or clamp: u-periodicity and v-clamping enter only
/// where a level is sampled, bilinearly as level 0 is. The reductions are chained in double
/// precision and each texel is rounded to 8 bits once (the levels are built row by row, a few
/// rows a level at a time). The levels add at most ⅓ of the image's texels plus
/// ⅔ max(W, H)/min(W, H) + 1 for those one texel high (a third of a texel for a 2:1 sky).
class ASRTTRACING_EXPORT ImageTexture final : public Texture
{
public:
  /// The most taps sampleAnisotropic spreads along a footprint's major axis.
  static constexpr int kMaxAnisotropicTaps = 16;

  /// Throws InvalidParameter unless width, height ≥ 1 and rgb holds 3 × width × height bytes.
  ImageTexture(int width, int height, std::vector<std::uint8_t> rgb);
  Color sample(double u, double v) const override;
  /// sampleAnisotropic: closer than sampleTrilinear to the brute-force box average over
  /// anisotropic footprints (measured in TestTextureFootprint).
  Color sampleFootprint(double u, double v, const TextureFootprint& f) const override;
  /// One trilinear lookup at OpenGL's level of detail log2 ρ, ρ the footprint's longer side in
  /// level-0 texels. ρ ≤ 1 (a footprint within a texel): sample(u, v).
  Color sampleTrilinear(double u, double v, const TextureFootprint& f) const;
  /// The footprint as the rectangle with its second moments (sides σ1 ≥ σ2, the singular values of
  /// its Jacobian in texels, along their singular directions), averaged by N = min(16, ⌈σ1/m⌉)
  /// trilinear taps along the major axis, m = max(σ2, 1) the minor side but at least a texel,
  /// each at the level of a box of side b = max(σ1/N, m), their centres spread evenly over the
  /// major side less b (so that a near-isotropic footprint's taps meet at its centre,
  /// continuously). σ1 ≤ 1 (within a texel): sample(u, v).
  Color sampleAnisotropic(double u, double v, const TextureFootprint& f) const;
  /// Bilinear sample of one mip level (0: sample(u, v)), level clamped to [0, levels() − 1].
  Color sampleLevel(int level, double u, double v) const;
  /// Trilinear lookup at a fractional level of detail (≤ 0: sample(u, v)).
  Color sampleLod(double u, double v, double lod) const;
  int width() const { return this->W; }
  int height() const { return this->H; }
  /// Mip levels, level 0 (the image) included; the last is 1 × 1.
  int levels() const { return static_cast<int>(this->Levels.size()); }
  int levelWidth(int level) const { return this->Levels[level].w; }
  int levelHeight(int level) const { return this->Levels[level].h; }
  /// Texel (i, j) of a level, as a colour (8-bit value / 255).
  Color texel(int level, int i, int j) const;
  /// Bytes the levels above level 0 take.
  std::size_t pyramidBytes() const { return this->Mips.size(); }

private:
  struct Level
  {
    int w = 0, h = 0;
    std::size_t offset = 0; ///< into Mips; level 0 is Rgb
  };
  const std::uint8_t* levelData(int level) const
  {
    return level == 0 ? this->Rgb.data() : this->Mips.data() + this->Levels[level].offset;
  }
  void buildPyramid();
  int W, H;
  std::vector<std::uint8_t> Rgb;
  std::vector<std::uint8_t> Mips;
  std::vector<Level> Levels;
};
}

#endif
