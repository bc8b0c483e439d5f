#include "Texture.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <sstream>
#include <string>

namespace asrt
{
namespace
{
[[noreturn]] void invalid(const std::string& msg)
{
  throw InvalidParameter(msg);
}

void requireColor(const Color& c, const char* what)
{
  for (int k = 0; k < 3; ++k)
  {
    if (!(c[k] >= 0.0 && c[k] <= 1.0))
    {
      std::ostringstream os;
      os << what << " must have channels in [0, 1], got (" << c.x() << ", " << c.y() << ", "
         << c.z() << ')';
      invalid(os.str());
    }
  }
}

using Vec2 = Eigen::Vector2d;

double cross(const Vec2& a, const Vec2& b)
{
  return a.x() * b.y() - a.y() * b.x();
}

/// One axis of a checker in check units (x = u·n): the sign g(x) = ±1, the parity of the check
/// column floor(x) mod n, and its primitive G(x) = ∫₀ˣ g. Over one period of n checks g integrates
/// to `ramp`: 0 for even n, 1 for odd n, whose first and last checks have the same colour.
struct CheckAxis
{
  explicit CheckAxis(int checks)
    : n(checks)
    , ramp(checks % 2 == 1 ? 1.0 : 0.0)
  {
  }

  double sign(double x) const
  {
    const double k = std::floor(x);
    const double column = k - this->n * std::floor(k / this->n); // exact for |k| < 2⁵³
    return std::fmod(column, 2.0) == 0.0 ? 1.0 : -1.0;
  }

  /// A ramp of `ramp` a period plus the triangle wave ∫₀ʳ (−1)^⌊ρ⌋ dρ of the position r in it.
  double primitive(double x) const
  {
    const double q = std::floor(x / this->n);
    const double r = x - q * this->n;
    const double r2 = r - 2.0 * std::floor(0.5 * r);
    return q * this->ramp + (r2 <= 1.0 ? r2 : 2.0 - r2);
  }

  /// Whether g is constant on (x − h, x + h): no check line that changes the sign lies inside.
  bool flat(double x, double h) const
  {
    if (this->n == 1)
      return true;
    // The first and last column touched (one for h = 0, even on a line).
    const double lo = std::floor(x - h), hi = std::max(lo, std::ceil(x + h) - 1.0);
    if (lo == hi)
      return true;
    // One line crossed, at x = hi: for odd n it changes no sign if it is a period's boundary.
    return hi - lo == 1.0 && this->n % 2 == 1 && hi - this->n * std::floor(hi / this->n) == 0.0;
  }

  /// The mean of g over [x − w/2, x + w/2], exactly (w > 0, not flat).
  double boxMean(double x, double w) const
  {
    // Beyond a million periods the mean over whole periods, ramp/n, is within 2/w of it, and the
    // primitive's difference would lose its digits.
    if (w > 1e6 * this->n)
      return this->ramp / this->n;
    return (this->primitive(x + 0.5 * w) - this->primitive(x - 0.5 * w)) / w;
  }

  int n;
  double ramp;
};

/// ∫ (G(X) − gc) h(Y) dY along the segment p → p + d, exactly: between the segment's crossings of
/// integer X (where G has its kinks) and of integer Y (where h jumps) the integrand is linear in
/// the segment's parameter, so the midpoint of each piece gives its integral.
double edgeIntegral(const CheckAxis& ax, const CheckAxis& ay, const Vec2& p, const Vec2& d,
                    double gc)
{
  if (d.y() == 0.0)
    return 0.0;
  constexpr double never = std::numeric_limits<double>::infinity();
  // The next integer each coordinate reaches, and the parameter λ ∈ (0, 1] at which it does; each
  // λ is computed afresh from its integer, so that none drifts.
  const double stepX = d.x() > 0.0 ? 1.0 : -1.0, stepY = d.y() > 0.0 ? 1.0 : -1.0;
  double kx = d.x() > 0.0 ? std::floor(p.x()) + 1.0 : std::ceil(p.x()) - 1.0;
  double ky = d.y() > 0.0 ? std::floor(p.y()) + 1.0 : std::ceil(p.y()) - 1.0;
  auto crossing = [](double k, double p0, double d0) { return d0 == 0.0 ? never : (k - p0) / d0; };
  double lx = crossing(kx, p.x(), d.x()), ly = crossing(ky, p.y(), d.y());
  double sum = 0.0, prev = 0.0;
  for (;;)
  {
    const double next = std::min({ lx, ly, 1.0 });
    const double mid = 0.5 * (prev + next);
    const double X = p.x() + mid * d.x(), Y = p.y() + mid * d.y();
    sum += (next - prev) * (ax.primitive(X) - gc) * ay.sign(Y);
    if (next >= 1.0)
      break;
    if (lx == next)
      lx = crossing(kx += stepX, p.x(), d.x());
    if (ly == next)
      ly = crossing(ky += stepY, p.y(), d.y());
    prev = next;
  }
  return sum * d.y();
}

/// Weights of the fine texels under each coarse texel along one axis of a mip reduction from
/// `fine` to `coarse` texels: coarse texel c spans [c·fine, (c + 1)·fine] and fine texel f spans
/// [f·coarse, (f + 1)·coarse], in units of 1/(fine·coarse) of the axis, so that overlaps are exact
/// integers. A coarse texel overlaps at most four fine ones (fine/coarse < 3).
struct Span
{
  int first = 0, count = 0;
  std::array<double, 4> weight{};
};

std::vector<Span> reductionSpans(int fine, int coarse)
{
  std::vector<Span> spans(coarse);
  for (int c = 0; c < coarse; ++c)
  {
    const long long lo = static_cast<long long>(c) * fine, hi = lo + fine;
    Span& s = spans[c];
    s.first = static_cast<int>(lo / coarse);
    const int last = static_cast<int>((hi - 1) / coarse);
    s.count = last - s.first + 1;
    for (int f = s.first; f <= last; ++f)
    {
      const long long flo = static_cast<long long>(f) * coarse, fhi = flo + coarse;
      s.weight[f - s.first] =
        static_cast<double>(std::min(hi, fhi) - std::max(lo, flo)) / static_cast<double>(fine);
    }
  }
  return spans;
}

/// One level above 0 while the pyramid is built: its spans over the level below and the last
/// kRows rows it made, unrounded.
struct PyramidLevel
{
  static constexpr int kRows = 4; // a coarse row spans at most four fine ones
  int w = 0;
  std::uint8_t* out = nullptr;
  std::vector<Span> sx, sy;
  std::vector<double> rows;
  int made[kRows] = { -1, -1, -1, -1 };
};

/// Adds weight × the fine row's reduction along u to `dst` (3 × coarse width).
template<class T>
void accumulateRow(const PyramidLevel& l, const T* src, double weight, double* dst)
{
  for (int i = 0; i < l.w; ++i)
  {
    const Span& s = l.sx[i];
    for (int a = 0; a < s.count; ++a)
    {
      const double w = weight * s.weight[a];
      const T* p = src + 3 * static_cast<std::size_t>(s.first + a);
      for (int ch = 0; ch < 3; ++ch)
        dst[3 * i + ch] += w * p[ch];
    }
  }
}

/// Row j of level k, unrounded: the exact area average of the unrounded rows below it (level 0's
/// bytes at the bottom), so that each stored texel is rounded to 8 bits once, not a rounding of
/// roundings. The row is also stored, rounded. Rows are asked for in increasing order at every
/// level, and consecutive coarse rows share at most one fine row, so the last kRows suffice.
const double* pyramidRow(std::vector<PyramidLevel>& levels, int k, int j, const std::uint8_t* rgb0,
                         int w0)
{
  PyramidLevel& l = levels[k];
  const int slot = j % PyramidLevel::kRows;
  double* dst = l.rows.data() + slot * 3 * static_cast<std::size_t>(l.w);
  if (l.made[slot] == j)
    return dst;
  std::fill(dst, dst + 3 * static_cast<std::size_t>(l.w), 0.0);
  const Span& s = l.sy[j];
  for (int b = 0; b < s.count; ++b)
  {
    const int fine = s.first + b;
    if (k == 1)
      accumulateRow(l, rgb0 + 3 * static_cast<std::size_t>(fine) * w0, s.weight[b], dst);
    else
      accumulateRow(l, pyramidRow(levels, k - 1, fine, rgb0, w0), s.weight[b], dst);
  }
  l.made[slot] = j;
  std::uint8_t* q = l.out + 3 * static_cast<std::size_t>(j) * l.w;
  for (int c = 0; c < 3 * l.w; ++c)
    q[c] = static_cast<std::uint8_t>(std::clamp(std::lround(dst[c]), 0L, 255L));
  return dst;
}

/// Bilinear between texel centres, periodic in u and clamped in v: ImageTexture::sample's
/// arithmetic, for any level.
Color bilinear(const std::uint8_t* rgb, int W, int H, double u, double v)
{
  if (!std::isfinite(u) || !std::isfinite(v))
    return Color::Zero();
  // Pixel centres sit at (i + ½)/W: the sample between centres i0 and i0 + 1 is x = u W − ½.
  const double x = (u - std::floor(u)) * W - 0.5;
  const double y = std::clamp(v * H - 0.5, 0.0, static_cast<double>(H - 1));
  const double x0f = std::floor(x), y0f = std::floor(y);
  const double fx = x - x0f, fy = y - y0f;
  // x ∈ [−½, W − ½): x0 ∈ {−1, …, W − 1}, wrapped periodically.
  int i0 = static_cast<int>(x0f);
  int i1 = i0 + 1;
  if (i0 < 0)
    i0 += W;
  if (i1 >= W)
    i1 -= W;
  const int j0 = static_cast<int>(y0f);
  const int j1 = std::min(j0 + 1, H - 1);
  auto px = [rgb, W](int i, int j)
  {
    const std::uint8_t* p = &rgb[3 * (static_cast<std::size_t>(j) * W + i)];
    return Color(p[0], p[1], p[2]);
  };
  const Color c = (1 - fy) * ((1 - fx) * px(i0, j0) + fx * px(i1, j0)) +
                  fy * ((1 - fx) * px(i0, j1) + fx * px(i1, j1));
  return c / 255.0;
}
}

// ---------------------------------------------------------------------------------------------
Color Texture::sampleFootprint(double u, double v, const TextureFootprint&) const
{
  return this->sample(u, v);
}

SolidTexture::SolidTexture(const Color& c)
  : C(c)
{
  requireColor(c, "solid texture colour");
}

// ---------------------------------------------------------------------------------------------
CheckerTexture::CheckerTexture(int nu, int nv, const Color& a, const Color& b)
  : Nu(nu)
  , Nv(nv)
  , A(a)
  , B(b)
{
  if (nu < 1 || nv < 1)
  {
    std::ostringstream os;
    os << "checker texture needs at least one check each way, got " << nu << " x " << nv;
    invalid(os.str());
  }
  requireColor(a, "checker texture colour a");
  requireColor(b, "checker texture colour b");
}

Color CheckerTexture::sample(double u, double v) const
{
  if (!std::isfinite(u) || !std::isfinite(v))
    return this->A;
  // Reduce to [0, 1) first so that the cell index fits an integer whatever the coordinate.
  const double fu = u - std::floor(u), fv = v - std::floor(v);
  const long i = std::min(static_cast<long>(fu * this->Nu), static_cast<long>(this->Nu - 1));
  const long j = std::min(static_cast<long>(fv * this->Nv), static_cast<long>(this->Nv - 1));
  return ((i + j) % 2 == 0) ? this->A : this->B;
}

Color CheckerTexture::sampleBox(double u, double v, const TextureFootprint& f) const
{
  if (!std::isfinite(u) || !std::isfinite(v) || !isFinite(f))
    return this->sample(u, v);
  const CheckAxis ax(this->Nu), ay(this->Nv);
  // In check units, about the centre reduced to the first period (the texture's period is 1).
  const double x = (u - std::floor(u)) * this->Nu, y = (v - std::floor(v)) * this->Nv;
  // The box whose marginal variances are the parallelogram's: s·a + t·b with s, t uniform on
  // [−½, ½] has variance (a² + b²)/12 along each axis, a box of width w has w²/12.
  const double wx = std::hypot(f.dudx, f.dudy) * this->Nu;
  const double wy = std::hypot(f.dvdx, f.dvdy) * this->Nv;
  const bool flatX = ax.flat(x, 0.5 * wx), flatY = ay.flat(y, 0.5 * wy);
  if (flatX && flatY)
    return this->sample(u, v);
  const double gx = flatX ? ax.sign(x) : ax.boxMean(x, wx);
  const double gy = flatY ? ay.sign(y) : ay.boxMean(y, wy);
  return this->mix(gx * gy);
}

Color CheckerTexture::sampleFootprint(double u, double v, const TextureFootprint& f) const
{
  if (!std::isfinite(u) || !std::isfinite(v) || !isFinite(f))
    return this->sample(u, v);
  const CheckAxis ax(this->Nu), ay(this->Nv);
  const Vec2 c((u - std::floor(u)) * this->Nu, (v - std::floor(v)) * this->Nv);
  Vec2 a(f.dudx * this->Nu, f.dvdx * this->Nv), b(f.dudy * this->Nu, f.dvdy * this->Nv);
  // Inside one check (its bounding box crosses no line that changes the colour): that check.
  const Vec2 half = 0.5 * (a.cwiseAbs() + b.cwiseAbs());
  if (ax.flat(c.x(), half.x()) && ay.flat(c.y(), half.y()))
    return this->sample(u, v);
  // The outline crosses about 2 (|a| + |b|)₁ check lines; beyond the cap, the box.
  if (2.0 * (a.lpNorm<1>() + b.lpNorm<1>()) > kMaxExactCrossings)
    return this->sampleBox(u, v, f);

  // Green's quotient is ∮/area: the rounding of the outline's terms, of size (|a| + |b|)², is
  // divided by the area |a × b|. A footprint within 1e-6 of a segment is thickened across its
  // longer side to that ratio, which moves the average by about as much.
  const double an = a.norm(), bn = b.norm();
  const double minArea = 1e-6 * (an + bn) * (an + bn);
  double area = cross(a, b);
  if (std::abs(area) < minArea)
  {
    const double target = area >= 0.0 ? minArea : -minArea;
    if (an >= bn)
      b += (target - area) / (an * an) * Vec2(-a.y(), a.x()); // a × perp(a) = |a|²
    else
      a -= (target - area) / (bn * bn) * Vec2(-b.y(), b.x());
    area = cross(a, b);
  }
  if (!(std::abs(area) > 0.0))
    return this->sample(u, v); // sides so small that their squares underflow
  // The corners c ∓ a/2 ∓ b/2 in order: ∮ over the outline a, b, −a, −b is the signed area's
  // orientation, so the quotient needs no sign. G is taken relative to its value at the centre
  // (∮ h dv = 0, so any constant may be subtracted) to keep the terms of the footprint's size.
  const double gc = ax.primitive(c.x());
  Vec2 p = c - 0.5 * (a + b);
  double integral = edgeIntegral(ax, ay, p, a, gc);
  p += a;
  integral += edgeIntegral(ax, ay, p, b, gc);
  p += b;
  integral += edgeIntegral(ax, ay, p, -a, gc);
  p -= a;
  integral += edgeIntegral(ax, ay, p, -b, gc);
  const double gh = integral / area;
  return std::isfinite(gh) ? this->mix(std::clamp(gh, -1.0, 1.0)) : this->sample(u, v);
}

// ---------------------------------------------------------------------------------------------
ImageTexture::ImageTexture(int width, int height, std::vector<std::uint8_t> rgb)
  : W(width)
  , H(height)
  , Rgb(std::move(rgb))
{
  if (width < 1 || height < 1)
  {
    std::ostringstream os;
    os << "image texture size must be positive, got " << width << " x " << height;
    invalid(os.str());
  }
  const std::size_t expected =
    3 * static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
  if (this->Rgb.size() != expected)
  {
    std::ostringstream os;
    os << "image texture of " << width << " x " << height << " pixels needs " << expected
       << " RGB bytes, got " << this->Rgb.size();
    invalid(os.str());
  }
  this->buildPyramid();
}

void ImageTexture::buildPyramid()
{
  // Floor halving, as OpenGL sizes its levels: ⌊w/2⌋ ≤ w/2 keeps the levels within ⅓ of the
  // image but for the tail one texel high.
  this->Levels.push_back(Level{ this->W, this->H, 0 });
  std::size_t bytes = 0;
  for (int w = this->W, h = this->H; w > 1 || h > 1;)
  {
    w = std::max(1, w / 2);
    h = std::max(1, h / 2);
    this->Levels.push_back(Level{ w, h, bytes });
    bytes += 3 * static_cast<std::size_t>(w) * static_cast<std::size_t>(h);
  }
  this->Mips.resize(bytes);
  if (this->Levels.size() < 2)
    return;
  std::vector<PyramidLevel> build(this->Levels.size());
  for (std::size_t k = 1; k < this->Levels.size(); ++k)
  {
    const Level& fine = this->Levels[k - 1];
    const Level& coarse = this->Levels[k];
    PyramidLevel& b = build[k];
    b.w = coarse.w;
    b.out = this->Mips.data() + coarse.offset;
    b.sx = reductionSpans(fine.w, coarse.w);
    b.sy = reductionSpans(fine.h, coarse.h);
    b.rows.assign(PyramidLevel::kRows * 3 * static_cast<std::size_t>(coarse.w), 0.0);
  }
  // The top level is one row: asking for it makes every row of every level once, in order.
  pyramidRow(build, static_cast<int>(build.size()) - 1, 0, this->Rgb.data(), this->W);
}

Color ImageTexture::sample(double u, double v) const
{
  return bilinear(this->Rgb.data(), this->W, this->H, u, v);
}

Color ImageTexture::texel(int level, int i, int j) const
{
  const Level& l = this->Levels[level];
  const std::uint8_t* p = this->levelData(level) + 3 * (static_cast<std::size_t>(j) * l.w + i);
  return Color(p[0], p[1], p[2]) / 255.0;
}

Color ImageTexture::sampleLevel(int level, double u, double v) const
{
  level = std::clamp(level, 0, this->levels() - 1);
  if (level == 0)
    return this->sample(u, v);
  const Level& l = this->Levels[level];
  return bilinear(this->levelData(level), l.w, l.h, u, v);
}

Color ImageTexture::sampleLod(double u, double v, double lod) const
{
  if (!(lod > 0.0))
    return this->sample(u, v);
  const int top = this->levels() - 1;
  if (lod >= top)
    return this->sampleLevel(top, u, v);
  const int k = static_cast<int>(lod);
  const double t = lod - k;
  return (1.0 - t) * this->sampleLevel(k, u, v) + t * this->sampleLevel(k + 1, u, v);
}

Color ImageTexture::sampleTrilinear(double u, double v, const TextureFootprint& f) const
{
  if (!isFinite(f))
    return this->sample(u, v);
  const double rho = std::max(std::hypot(f.dudx * this->W, f.dvdx * this->H),
                              std::hypot(f.dudy * this->W, f.dvdy * this->H));
  if (!(rho > 1.0))
    return this->sample(u, v);
  return this->sampleLod(u, v, std::log2(rho));
}

Color ImageTexture::sampleAnisotropic(double u, double v, const TextureFootprint& f) const
{
  if (!isFinite(f))
    return this->sample(u, v);
  // The Jacobian in level-0 texels, columns the screen axes; JJᵀ = [[p, q], [q, r]] is 12 times
  // the footprint's covariance, and a rectangle of sides σ1, σ2 along its eigenvectors has the
  // same.
  const double jux = f.dudx * this->W, jvx = f.dvdx * this->H;
  const double juy = f.dudy * this->W, jvy = f.dvdy * this->H;
  const double p = jux * jux + juy * juy, r = jvx * jvx + jvy * jvy, q = jux * jvx + juy * jvy;
  const double halfDiff = 0.5 * (p - r), d = std::hypot(halfDiff, q);
  const double s1 = std::sqrt(0.5 * (p + r) + d);
  if (!(s1 > 1.0))
    return this->sample(u, v); // within a texel (or NaN from an overflow): the bilinear sample
  const double s2 = std::abs(jux * jvy - juy * jvx) / s1; // σ1σ2 = |det J|
  // The major eigenvector, from whichever of its two forms does not cancel.
  Vec2 e = halfDiff >= 0.0 ? Vec2(halfDiff + d, q) : Vec2(q, d - halfDiff);
  const double en = e.norm();
  e = en > 0.0 ? Vec2(e / en) : Vec2(1.0, 0.0);
  // A texel is the finest detail there is: the minor side counts as at least one, so that a
  // footprint of up to a texel (σ1 ≤ 1) has one tap at level 0, the bilinear sample, and the taps
  // leave the centre continuously as σ1 grows past it.
  const double minor = std::max(s2, 1.0);
  const int n =
    static_cast<int>(std::min(static_cast<double>(kMaxAnisotropicTaps), std::ceil(s1 / minor)));
  const double box = std::max(s1 / n, minor);
  const double lod = std::log2(box);
  if (n <= 1)
    return this->sampleLod(u, v, lod);
  // Tap centres evenly over the major side less one box: the boxes cover it, overlapping where
  // σ1/σ2 is not a whole number, abutting when the cap is reached.
  const double span = s1 - box;
  Color sum = Color::Zero();
  for (int k = 0; k < n; ++k)
  {
    const double x = span * (static_cast<double>(k) / (n - 1) - 0.5);
    sum += this->sampleLod(u + x * e.x() / this->W, v + x * e.y() / this->H, lod);
  }
  return sum / n;
}

Color ImageTexture::sampleFootprint(double u, double v, const TextureFootprint& f) const
{
  return this->sampleAnisotropic(u, v, f);
}
}
