#include "FrameInterpolation.h"

#include "SplatKernel.h"

#include <omp.h>
#ifdef __SSE4_1__
#include <smmintrin.h>
#else
#include <emmintrin.h>
#endif

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <limits>

namespace asrt
{
const char* toString(PixelClass c)
{
  switch (c)
  {
    case PixelClass::Matched:
      return "matched";
    case PixelClass::OneSided:
      return "one-sided";
    case PixelClass::HoleFilled:
      return "hole-filled";
    case PixelClass::Ambiguous:
      return "ambiguous";
    case PixelClass::Retraced:
      return "re-traced";
  }
  return "?";
}

std::array<double, kPixelClassCount> InterpolatedFrame::fractions() const
{
  std::array<double, kPixelClassCount> f{};
  for (const PixelClass c : this->pixelClass)
    f[static_cast<std::size_t>(c)] += 1;
  const double n = std::max<std::size_t>(1, this->pixelClass.size());
  for (double& x : f)
    x /= n;
  return f;
}

namespace
{
/// A splat counts for visibility where its weight reaches this; lighter touches (its fringe)
/// blend but never hide what lies behind.
constexpr float kVisibleWeight = 0.2f;
/// Frames smaller than this are rendered on one thread: a parallel region costs more than it
/// saves there (a time slice, on a busy machine).
constexpr std::size_t kParallelPixels = 16384;
/// How many list entries ahead of the one being drawn its splat is prefetched.
constexpr std::int64_t kPrefetchAhead = 16;

using Accumulator = InterpolationWorkspace::Accumulator;

/// A splat's colour at t as drawn: (r, g, b, 1), so that one multiply-add per touch updates the
/// colour sums and the weight together.
using Color4 = __m128;

/// (c[0], c[1], c[2], 1) as floats. With SSE4.1 (the x86-64-v2 baseline) from the bytes at once:
/// four are read, the fourth dropped for the 1 (it is the next field of the splat).
inline Color4 colorOf(const std::uint8_t* c)
{
#ifdef __SSE4_1__
  static_assert(offsetof(SplatSet::Splat, other) + 4 <= sizeof(SplatSet::Splat),
                "the colour bytes are read four at a time");
  std::uint32_t bytes;
  std::memcpy(&bytes, c, 4);
  return _mm_blend_ps(
    _mm_cvtepi32_ps(_mm_cvtepu8_epi32(_mm_cvtsi32_si128(static_cast<int>(bytes)))),
    _mm_set1_ps(1.0f), 8);
#else
  return _mm_setr_ps(static_cast<float>(c[0]), static_cast<float>(c[1]), static_cast<float>(c[2]),
                     1.0f);
#endif
}

/// Adds one splat's touch of weight w (> 0) to a pixel. Visibility without a second pass: a
/// touch that counts and lies in front of everything gathered by more than its margin discards
/// it; one behind the front's limit is dropped; the rest blend. The limit never lies in front of
/// the nearest key (it is the front of a touch no nearer than that key), so a discarding touch
/// lowers the limit to its own front just as a blending one does: min(limit, key + margin) either
/// way, and only the sums depend on the comparison (branch-free but for the drop, which is rare
/// and well predicted).
inline void deposit(Accumulator& a, float w, float key, float margin, Color4 color,
                    float sideWeight, std::int32_t index, std::uint8_t cls)
{
  if (key > a.limit)
    return; // behind the front surface here
  const bool visible = w >= kVisibleWeight;
  const float front = key + margin;
  __m128 sum = _mm_load_ps(&a.r);
  if (visible && front < a.nearest)
    sum = _mm_setzero_ps();
  a.limit = visible ? std::min(a.limit, front) : a.limit;
  const bool nearer = key < a.nearest;
  a.nearest = nearer ? key : a.nearest;
  a.best = nearer ? index : a.best;
  a.cls = nearer ? cls : a.cls;
  const float ws = w * sideWeight;
  _mm_store_ps(&a.r, _mm_add_ps(sum, _mm_mul_ps(_mm_set1_ps(ws), color)));
}

/// The footprint map M with its singular values clamped to [1, maxMag] (a splat covers at least
/// its own pixel, at most maxMag pixels per source pixel along any axis): its inverse and the
/// half-extents of the image of [−1, 1]². From the eigen-decomposition of MᵀM = V Σ² Vᵀ: the
/// clamped map is M V diag(σ'/σ) Vᵀ, its inverse V diag(1/σ') Uᵀ with U = M V / σ.
void clampedFootprint(const float m[4], float maxMag, float inv[4], float& hx, float& hy)
{
  const float a = m[0] * m[0] + m[2] * m[2], b = m[0] * m[1] + m[2] * m[3],
              c = m[1] * m[1] + m[3] * m[3];
  const float mean = 0.5f * (a + c), dev = std::sqrt(0.25f * (a - c) * (a - c) + b * b);
  const float l1 = mean + dev, l2 = std::max(0.0f, mean - dev);
  // v1: eigenvector of the larger eigenvalue; v2 ⟂ v1.
  float v1x, v1y;
  if (std::abs(b) > 1e-12f * (a + c))
  {
    v1x = b;
    v1y = l1 - a;
    if (std::abs(v1x) + std::abs(v1y) < 1e-12f)
    {
      v1x = l1 - c;
      v1y = b;
    }
    const float norm = 1.0f / std::sqrt(v1x * v1x + v1y * v1y);
    v1x *= norm;
    v1y *= norm;
  }
  else if (a >= c)
  {
    v1x = 1;
    v1y = 0;
  }
  else
  {
    v1x = 0;
    v1y = 1;
  }
  const float v2x = -v1y, v2y = v1x;
  const float s1 = std::sqrt(l1), s2 = std::sqrt(l2);
  // U's columns: M v / σ; a vanishing σ leaves u2 ⟂ u1 (either orientation covers the pixel).
  float u1x = v1x, u1y = v1y;
  if (s1 > 1e-6f)
  {
    u1x = (m[0] * v1x + m[1] * v1y) / s1;
    u1y = (m[2] * v1x + m[3] * v1y) / s1;
  }
  float u2x = -u1y, u2y = u1x;
  if (s2 > 1e-6f)
  {
    u2x = (m[0] * v2x + m[1] * v2y) / s2;
    u2y = (m[2] * v2x + m[3] * v2y) / s2;
  }
  const float c1 = std::clamp(s1, 1.0f, maxMag), c2 = std::clamp(s2, 1.0f, maxMag);
  // M' = c1 u1 v1ᵀ + c2 u2 v2ᵀ;  M'⁻¹ = v1 u1ᵀ / c1 + v2 u2ᵀ / c2.
  const float m00 = c1 * u1x * v1x + c2 * u2x * v2x, m01 = c1 * u1x * v1y + c2 * u2x * v2y;
  const float m10 = c1 * u1y * v1x + c2 * u2y * v2x, m11 = c1 * u1y * v1y + c2 * u2y * v2y;
  hx = std::abs(m00) + std::abs(m01);
  hy = std::abs(m10) + std::abs(m11);
  inv[0] = v1x * u1x / c1 + v2x * u2x / c2;
  inv[1] = v1x * u1y / c1 + v2x * u2y / c2;
  inv[2] = v1y * u1x / c1 + v2y * u2x / c2;
  inv[3] = v1y * u1y / c1 + v2y * u2y / c2;
}

/// Fills the pixels no splat reached (class HoleFilled, source −1). Few small holes grow inwards
/// from their rims, each pass giving a hole pixel the mean of its 8-neighbours known before the
/// pass (deterministic, O(holes)); large ones, or what remains after 64 passes, by push-pull.
/// ws.allHoles lists the holes in pixel order (renderFrame collects them while resolving).
void fillHoles(InterpolatedFrame& out, InterpolationWorkspace& ws)
{
  const int W = out.width, H = out.height;
  const std::size_t n = static_cast<std::size_t>(W) * H;
  ws.holes.clear();
  if (static_cast<std::size_t>(out.holes) * 50 <= n)
  {
    ws.holes = ws.allHoles;
    // A pixel filled in pass k is marked −2 − k in `source` until the end.
    for (int pass = 0; pass < 64 && !ws.holes.empty(); ++pass)
    {
      ws.stillHoles.clear();
      for (const std::int32_t p : ws.holes)
      {
        const int i = p % W, j = p / W;
        int sum[3] = { 0, 0, 0 }, count = 0;
        for (int dj = -1; dj <= 1; ++dj)
          for (int di = -1; di <= 1; ++di)
          {
            const int x = i + di, y = j + dj;
            if ((di == 0 && dj == 0) || x < 0 || x >= W || y < 0 || y >= H)
              continue;
            const std::size_t q = static_cast<std::size_t>(y) * W + x;
            const std::int32_t mark = out.source[q];
            if (mark >= 0 || (mark <= -2 && -2 - mark < pass))
            {
              for (int c = 0; c < 3; ++c)
                sum[c] += out.rgb[3 * q + c];
              ++count;
            }
          }
        if (count == 0)
        {
          ws.stillHoles.push_back(p);
          continue;
        }
        for (int c = 0; c < 3; ++c)
          out.rgb[3 * static_cast<std::size_t>(p) + c] =
            static_cast<std::uint8_t>((sum[c] + count / 2) / count);
        out.source[static_cast<std::size_t>(p)] = -2 - pass;
      }
      ws.holes.swap(ws.stillHoles);
    }
    for (const std::int32_t p : ws.allHoles)
      if (out.source[static_cast<std::size_t>(p)] <= -2)
        out.source[static_cast<std::size_t>(p)] = -1;
    if (ws.holes.empty())
      return;
  }
  // Push-pull over the whole frame for what is left.
  ws.fill.resize(3 * n);
  ws.fillWeight.resize(n);
  std::vector<std::uint8_t> pending(ws.holes.empty() ? 0 : n, 0);
  for (const std::int32_t p : ws.holes)
    pending[static_cast<std::size_t>(p)] = 1;
#pragma omp parallel for schedule(static) if (n > kParallelPixels)
  for (std::int64_t p = 0; p < static_cast<std::int64_t>(n); ++p)
  {
    const std::size_t q = static_cast<std::size_t>(p);
    const bool hole = pending.empty() ? out.source[q] == -1 : pending[q] != 0;
    ws.fillWeight[q] = hole ? 0.0f : 1.0f;
    for (int c = 0; c < 3; ++c)
      ws.fill[3 * q + c] = out.rgb[3 * q + c];
  }
  if (!pushPullFill(W, H, 3, ws.fill.data(), ws.fillWeight.data(), &ws.pyramid))
    return; // nothing at all was drawn: the frame stays black
#pragma omp parallel for schedule(static) if (n > kParallelPixels)
  for (std::int64_t p = 0; p < static_cast<std::int64_t>(n); ++p)
    if (ws.fillWeight[static_cast<std::size_t>(p)] == 0.0f)
      for (int c = 0; c < 3; ++c)
        out.rgb[3 * static_cast<std::size_t>(p) + c] = static_cast<std::uint8_t>(
          std::clamp(ws.fill[3 * static_cast<std::size_t>(p) + c], 0.0f, 255.0f) + 0.5f);
}

/// Which of the four groups of splats (A's mutual, A's other, B's mutual, B's other) a frame
/// draws, and at what weight.
struct GroupSelection
{
  bool draw[4];
  float weight[4];
};

/// Both sides: a mutual pair from the frame nearer in t at full weight, every other splat from
/// its own frame at (1 − t) or t. One side: its own groups at full weight.
GroupSelection selectGroups(SplatSides sides, float tf)
{
  GroupSelection g;
  if (sides == SplatSides::Both)
  {
    g.draw[0] = tf < 0.5f;
    g.draw[1] = tf < 1.0f;
    g.draw[2] = tf >= 0.5f;
    g.draw[3] = tf > 0.0f;
    g.weight[0] = g.weight[2] = 1.0f;
    g.weight[1] = 1.0f - tf;
    g.weight[3] = tf;
  }
  else
  {
    const bool a = sides == SplatSides::AOnly;
    g.draw[0] = g.draw[1] = a;
    g.draw[2] = g.draw[3] = !a;
    std::fill(g.weight, g.weight + 4, 1.0f);
  }
  return g;
}

/// The ends are the traced frames themselves: the colours of A's splats (offset 0) or B's (n).
void copyTracedFrame(const SplatSet& set, std::size_t offset, InterpolatedFrame& out)
{
  const std::size_t n = set.pixelCount();
  for (std::size_t p = 0; p < n; ++p)
  {
    const SplatSet::Splat& sp = set.splats[offset + p];
    std::copy(sp.color, sp.color + 3, &out.rgb[3 * p]);
    out.pixelClass[p] = static_cast<PixelClass>(sp.cls & ~SplatSet::kMutual);
    out.source[p] = static_cast<std::int32_t>(offset + p);
  }
}

/// What drawing and resolving the bands of one frame read. The arrays are plain pointers, and
/// the functions below copy what their loops use into locals: the deposits store bytes, which
/// may alias anything, and would otherwise have every field loaded again after each touch.
struct BandPass
{
  BandPass(const SplatSet& splatSet, double t, SplatSides drawn, InterpolatedFrame& out,
           double horizonRadius)
    : set(splatSet)
    , splats(splatSet.splats.data())
    , bandSplats(splatSet.bandSplats.data())
    , bandReach(splatSet.bandReach.data())
    , bandStart(splatSet.bandStart.data())
    , jacobianDeviation(splatSet.jacobianDeviation.data())
    , layerStride(splatSet.layerStride)
    , W(splatSet.width)
    , H(splatSet.height)
    , rows(splatSet.bandRows)
    , slice(1 + std::min(SplatSet::kSegments - 1, static_cast<int>(t * SplatSet::kSegments)))
    , n(splatSet.pixelCount())
    , stride(splatSet.width + 2)
    , tf(static_cast<float>(t))
    , maxMag(splatSet.options.maxMagnification)
    , maxExtent(footprintReach(this->maxMag, kDrawReachMargin))
    , sides(drawn)
    , groups(selectGroups(drawn, this->tf))
    , rgbOut(out.rgb.data())
    , classOut(out.pixelClass.data())
    , sourceOut(out.source.data())
    , hitRadius(horizonRadius > 0.0 ? splatSet.hitRadius.data() : nullptr)
    , horizon(static_cast<float>(horizonRadius))
  {
  }

  const SplatSet& set;
  const SplatSet::Splat* splats;
  const std::int32_t* bandSplats;
  const std::array<std::uint8_t, 2>* bandReach;
  const std::int64_t* bandStart;
  const float* jacobianDeviation;
  float layerStride;
  int W, H, rows;
  int slice; ///< the slice of t whose lists are drawn, besides the static ones
  std::size_t n;
  /// Accumulators of a band: its rows plus a guard row above and below and a guard column on
  /// each side, so that the four taps of a bilinear splat need no bounds checks.
  int stride;
  float tf, maxMag;
  float maxExtent; ///< no footprint reaches further from its centre than this
  SplatSides sides;
  GroupSelection groups;
  std::uint8_t* rgbOut;
  PixelClass* classOut;
  std::int32_t* sourceOut;
  /// Where the hole at t hides scene points (renderFrame's horizonRadius): each splat's distance
  /// from its centre, null where nothing is hidden.
  const float* hitRadius;
  float horizon;
};

/// The bands into ws.bandOrder, those with the most list entries to draw first, so that the
/// threads finish together (each band's pixels are what they are whichever thread draws it,
/// and whenever).
void orderBandsByWork(const BandPass& pass, int bands, InterpolationWorkspace& ws)
{
  const SplatSet& set = pass.set;
  std::vector<int>& order = ws.bandOrder;
  std::vector<std::int64_t>& work = ws.bandWork;
  order.resize(static_cast<std::size_t>(bands));
  work.assign(static_cast<std::size_t>(bands), 0);
  for (int b = 0; b < bands; ++b)
  {
    order[static_cast<std::size_t>(b)] = b;
    for (int gs = 0; gs < 8; ++gs)
      if (pass.groups.draw[gs % 4])
      {
        const std::size_t list = set.listIndex(b, gs < 4 ? 0 : pass.slice, gs % 4);
        work[static_cast<std::size_t>(b)] += set.bandStart[list + 1] - set.bandStart[list];
      }
  }
  std::stable_sort(order.begin(), order.end(),
                   [&](int x, int y) {
                     return work[static_cast<std::size_t>(x)] > work[static_cast<std::size_t>(y)];
                   });
}

/// One splat's touches of the four pixels around its centre, a[0] the accumulator of the one
/// below and left of it, (ax, ay) the centre's offset from that pixel.
inline void drawBilinear(Accumulator* a, int stride, float ax, float ay, float key, float margin,
                         Color4 color, float sideWeight, std::int32_t index, std::uint8_t cls)
{
  float w00, w10, w01, w11;
  bilinearWeights(ax, ay, w00, w10, w01, w11);
  // Usually all four taps touch: one test for them (the same deposits, in order).
  if ((w00 > 0) & (w10 > 0) & (w01 > 0) & (w11 > 0))
  {
    deposit(a[0], w00, key, margin, color, sideWeight, index, cls);
    deposit(a[1], w10, key, margin, color, sideWeight, index, cls);
    deposit(a[stride], w01, key, margin, color, sideWeight, index, cls);
    deposit(a[stride + 1], w11, key, margin, color, sideWeight, index, cls);
    return;
  }
  if (w00 > 0)
    deposit(a[0], w00, key, margin, color, sideWeight, index, cls);
  if (w10 > 0)
    deposit(a[1], w10, key, margin, color, sideWeight, index, cls);
  if (w01 > 0)
    deposit(a[stride], w01, key, margin, color, sideWeight, index, cls);
  if (w11 > 0)
    deposit(a[stride + 1], w11, key, margin, color, sideWeight, index, cls);
}

/// One splat's touches of the pixels its clamped footprint m (at its side time) covers, within
/// the band's rows [r0, r1): the tent kernel in the splat's own coordinates.
inline void drawFootprint(const float m[4], float maxMag, float x, float y, int W, int r0, int r1,
                          Accumulator* origin, int stride, float key, float margin, Color4 color,
                          float sideWeight, std::int32_t index, std::uint8_t cls)
{
  float inv[4], hx, hy;
  clampedFootprint(m, maxMag, inv, hx, hy);
  const int xa = std::max(0, static_cast<int>(std::ceil(x - hx)));
  const int xb = std::min(W - 1, static_cast<int>(std::floor(x + hx)));
  const int ya = std::max(r0, static_cast<int>(std::ceil(y - hy)));
  const int yb = std::min(r1 - 1, static_cast<int>(std::floor(y + hy)));
  for (int py = ya; py <= yb; ++py)
  {
    const float ry = static_cast<float>(py) - y;
    Accumulator* line = origin + static_cast<std::ptrdiff_t>(py) * stride;
    for (int px = xa; px <= xb; ++px)
    {
      const float rx = static_cast<float>(px) - x;
      const float u = inv[0] * rx + inv[1] * ry, v = inv[2] * rx + inv[3] * ry;
      const float w = splatWeight(u, v);
      if (w > 0.0f)
        deposit(line[px], w, key, margin, color, sideWeight, index, cls);
    }
  }
}

/// Draws list `list` into the accumulators of the band of rows [r0, r1) (pixel (px, py) at
/// origin[py · stride + px]): its splats of one side at side time s, in list order; `Hides`: the
/// splats within the horizon at t (BandPass::hitRadius) left out, a test the frames without one
/// do not pay for.
template<bool Hides>
inline void drawList(const BandPass& pass, std::size_t list, int r0, int r1, Accumulator* origin,
                     bool sideB, float s, float sideWeight)
{
  const SplatSet::Splat* const splats = pass.splats;
  const std::int32_t* const bandSplats = pass.bandSplats;
  const std::array<std::uint8_t, 2>* const bandReach = pass.bandReach;
  const float* const jacobianDeviation = pass.jacobianDeviation;
  const float* const hitRadius = pass.hitRadius;
  const float horizon = pass.horizon;
  const std::array<float, 4>* const jacobians = pass.set.jacobians.data();
  const float layerStride = pass.layerStride, maxMag = pass.maxMag, maxExtent = pass.maxExtent;
  const int W = pass.W, stride = pass.stride;
  const std::size_t n = pass.n;
  // One side alone shows its own frame's colours: what each frame says is there.
  const __m128 blend = _mm_set1_ps(pass.sides == SplatSides::Both ? s : 0.0f);
  std::size_t rowStart = std::numeric_limits<std::size_t>::max() / 2;
  int row = 0;
  const std::int64_t end = pass.bandStart[list + 1];
  // s in 255ths, rounded down and up: s · 255 < lo ⇔ below < lo, s · 255 > hi ⇔ above > hi.
  const int below = static_cast<int>(std::floor(s * 255.0f)),
            above = static_cast<int>(std::ceil(s * 255.0f));
  for (std::int64_t e = pass.bandStart[list]; e < end; ++e)
  {
    // Turned away unread when it cannot reach this band at this t.
    const auto& r = bandReach[e];
    if (below < r[0] || above > r[1])
      continue;
    const std::int32_t index = bandSplats[e];
    if constexpr (Hides)
      if (hitRadius[index] <= horizon)
        continue; // swallowed by the hole at t
    const SplatSet::Splat& sp = splats[index];
    // The lists skip through the splats (other groups, other bands): too irregular for the
    // hardware prefetcher, so the splats some way ahead are asked for explicitly.
    if (e + kPrefetchAhead < end)
      _mm_prefetch(reinterpret_cast<const char*>(&splats[bandSplats[e + kPrefetchAhead]]),
                   _MM_HINT_T0);
    const std::size_t pix = static_cast<std::size_t>(index) - (sideB ? n : 0);
    if (pix < rowStart || pix >= rowStart + static_cast<std::size_t>(W))
    {
      row = static_cast<int>(pix / W);
      rowStart = static_cast<std::size_t>(row) * W;
    }
    const float x = static_cast<float>(pix - rowStart) + s * sp.dx;
    const float y = static_cast<float>(row) + s * sp.dy;
    // Many listed splats lie outside this band at this t (those listed in two bands, or for a
    // whole slice of t): they are turned away before their key and colour are made.
    const bool bilinear =
      sp.footprint < 0 || s * jacobianDeviation[sp.footprint] <= kBilinearDeviation;
    const float fx = std::floor(x), fy = std::floor(y);
    if (bilinear
          ? !(fx >= -1.0f && fx < static_cast<float>(W) && fy >= static_cast<float>(r0 - 1) &&
              fy < static_cast<float>(r1))
          : !(y + maxExtent >= static_cast<float>(r0) && y - maxExtent < static_cast<float>(r1)))
      continue; // no tap inside the band (NaN positions end here too)
    const float key = static_cast<float>(sp.layer) * layerStride + sp.length + s * sp.dLength;
    const float margin = sp.margin;
    const std::uint8_t cls = sp.cls;
    // Colour (r, g, b, 1) at t: own + blend · (other − own).
    const __m128 own = colorOf(sp.color), other = colorOf(sp.other);
    const Color4 color = _mm_add_ps(own, _mm_mul_ps(blend, _mm_sub_ps(other, own)));

    if (bilinear)
    {
      drawBilinear(origin + static_cast<std::ptrdiff_t>(fy) * stride +
                     static_cast<std::ptrdiff_t>(fx),
                   stride, x - fx, y - fy, key, margin, color, sideWeight, index, cls);
      continue;
    }
    const auto& d = jacobians[sp.footprint];
    const float m[4] = { 1.0f + s * (d[0] - 1.0f), s * d[1], s * d[2], 1.0f + s * (d[3] - 1.0f) };
    drawFootprint(m, maxMag, x, y, W, r0, r1, origin, stride, key, margin, color, sideWeight, index,
                  cls);
  }
}

/// Draws every list band b draws at t: the static lists of the groups drawn, then their lists of
/// t's slice.
inline void drawBand(const BandPass& pass, int b, int r0, int r1, Accumulator* origin)
{
  for (int gs = 0; gs < 8; ++gs)
  {
    const int g = gs % 4;
    if (!pass.groups.draw[g])
      continue;
    const bool sideB = g >= 2;
    const float s = sideB ? 1.0f - pass.tf : pass.tf;
    const std::size_t list = pass.set.listIndex(b, gs < 4 ? 0 : pass.slice, g);
    if (pass.hitRadius)
      drawList<true>(pass, list, r0, r1, origin, sideB, s, pass.groups.weight[g]);
    else
      drawList<false>(pass, list, r0, r1, origin, sideB, s, pass.groups.weight[g]);
  }
}

/// Resolves the band of rows [r0, r1) into the output, emptying its accumulators and guard cells
/// as it reads them; its holes (pixels no splat reached) into bandHoles, in pixel order. Returns
/// how many there are.
inline std::int64_t resolveBand(const BandPass& pass, int r0, int r1, Accumulator* origin,
                                const Accumulator& empty, std::vector<std::int32_t>& bandHoles)
{
  const int W = pass.W, stride = pass.stride;
  std::uint8_t* const rgbOut = pass.rgbOut;
  PixelClass* const classOut = pass.classOut;
  std::int32_t* const sourceOut = pass.sourceOut;
  std::int64_t holes = 0;
  std::fill(origin + static_cast<std::ptrdiff_t>(r0 - 1) * stride - 1,
            origin + static_cast<std::ptrdiff_t>(r0) * stride - 1, empty);
  std::fill(origin + static_cast<std::ptrdiff_t>(r1) * stride - 1,
            origin + static_cast<std::ptrdiff_t>(r1 + 1) * stride - 1, empty);
  for (int py = r0; py < r1; ++py)
  {
    Accumulator* line = origin + static_cast<std::ptrdiff_t>(py) * stride;
    line[-1] = line[W] = empty;
    for (int px = 0; px < W; ++px)
    {
      const Accumulator a = line[px];
      line[px] = empty;
      const std::size_t p = static_cast<std::size_t>(py) * W + px;
      if (!(a.weight > 0.0f))
      {
        ++holes;
        bandHoles.push_back(static_cast<std::int32_t>(p));
        classOut[p] = PixelClass::HoleFilled;
        sourceOut[p] = -1;
        rgbOut[3 * p] = rgbOut[3 * p + 1] = rgbOut[3 * p + 2] = 0;
        continue;
      }
      // round(clamp(sum / weight, 0, 255)) per channel, four lanes at once.
      const __m128 mean = _mm_mul_ps(_mm_load_ps(&a.r), _mm_set1_ps(1.0f / a.weight));
      const __m128i rounded = _mm_cvttps_epi32(_mm_add_ps(
        _mm_min_ps(_mm_max_ps(mean, _mm_setzero_ps()), _mm_set1_ps(255.0f)), _mm_set1_ps(0.5f)));
      alignas(16) std::int32_t channels[4];
      _mm_store_si128(reinterpret_cast<__m128i*>(channels), rounded);
      rgbOut[3 * p] = static_cast<std::uint8_t>(channels[0]);
      rgbOut[3 * p + 1] = static_cast<std::uint8_t>(channels[1]);
      rgbOut[3 * p + 2] = static_cast<std::uint8_t>(channels[2]);
      sourceOut[p] = a.best;
      classOut[p] = static_cast<PixelClass>(a.cls & ~SplatSet::kMutual);
    }
  }
  return holes;
}

/// Draws and resolves every band, on the OpenMP threads, bands handed out in ws.bandOrder.
/// Returns the number of holes; each band's are in ws.bandHoles.
std::int64_t drawAndResolveBands(const BandPass& pass, int bands, InterpolationWorkspace& ws)
{
  const bool emptied = ws.bandsEmpty;
  ws.bandsEmpty = false; // until this render has emptied them again
  const int rows = pass.rows, H = pass.H, stride = pass.stride;
  const std::vector<int>& order = ws.bandOrder;
  std::int64_t holes = 0;
#pragma omp parallel reduction(+ : holes) if (pass.n > kParallelPixels)
  {
    // Resolving a band empties what it read (while it is in cache) and its guard cells, ready
    // for the thread's next band, and so for the next frame: accumulators are only filled anew
    // when they grow, or when a render did not finish.
    auto& acc = ws.bands[static_cast<std::size_t>(omp_get_thread_num())];
    const float inf = std::numeric_limits<float>::infinity();
    const Accumulator empty{ 0, 0, 0, 0, inf, inf, -1, 0, { 0, 0, 0 } };
    const std::size_t cells = static_cast<std::size_t>(rows + 2) * stride;
    if (!emptied || acc.size() < cells)
      acc.assign(std::max(cells, acc.size()), empty);
#pragma omp for schedule(dynamic, 1)
    for (int k = 0; k < bands; ++k)
    {
      const int b = order[static_cast<std::size_t>(k)];
      std::vector<std::int32_t>& bandHoles = ws.bandHoles[static_cast<std::size_t>(b)];
      bandHoles.clear();
      const int r0 = b * rows, r1 = std::min(H, r0 + rows);
      // Pixel (px, py) of the band is origin[py · stride + px].
      Accumulator* origin = acc.data() + stride + 1 - static_cast<std::ptrdiff_t>(r0) * stride;
      drawBand(pass, b, r0, r1, origin);
      holes += resolveBand(pass, r0, r1, origin, empty, bandHoles);
    }
  }
  ws.bandsEmpty = true;
  return holes;
}
}

void renderFrame(const SplatSet& set, double tIn, InterpolatedFrame& out,
                 InterpolationWorkspace& ws, SplatSides sides, double horizonRadius)
{
  requireFinite(tIn, "interpolation time");
  if (!(horizonRadius >= 0.0) || std::isinf(horizonRadius))
    throw InvalidParameter("renderFrame: the horizon's radius must be finite and 0 or more");
  if (horizonRadius > 0.0 && set.hitRadius.size() != set.splats.size())
    throw InvalidParameter("renderFrame: the splats have no hit radii (buildSplats makes them)");
  const double t = std::clamp(tIn, 0.0, 1.0);
  const int W = set.width, H = set.height;
  const std::size_t n = set.pixelCount();
  out.width = W;
  out.height = H;
  out.t = t;
  out.rgb.resize(3 * n);
  out.pixelClass.resize(n);
  out.source.resize(n);
  out.holes = 0;
  if (sides == SplatSides::Both && (t == 0.0 || t == 1.0))
  {
    copyTracedFrame(set, t == 0.0 ? 0 : n, out);
    return;
  }
  const BandPass pass(set, t, sides, out, horizonRadius);
  const int bands = (H + pass.rows - 1) / pass.rows;
  const int threads = omp_get_max_threads();
  if (static_cast<int>(ws.bands.size()) < threads)
    ws.bands.resize(static_cast<std::size_t>(threads));
  if (ws.bandHoles.size() < static_cast<std::size_t>(bands))
    ws.bandHoles.resize(static_cast<std::size_t>(bands));
  orderBandsByWork(pass, bands, ws);
  const std::int64_t holes = drawAndResolveBands(pass, bands, ws);
  out.holes = holes;
  if (holes > 0)
  {
    ws.allHoles.clear();
    for (int b = 0; b < bands; ++b)
      ws.allHoles.insert(ws.allHoles.end(), ws.bandHoles[static_cast<std::size_t>(b)].begin(),
                         ws.bandHoles[static_cast<std::size_t>(b)].end());
    fillHoles(out, ws);
  }
}

void renderDisagreement(const SplatSet& set, double t, std::vector<std::uint8_t>& out,
                        InterpolationWorkspace& ws)
{
  renderFrame(set, t, ws.sideA, ws, SplatSides::AOnly);
  renderFrame(set, t, ws.sideB, ws, SplatSides::BOnly);
  const std::size_t n = set.pixelCount();
  out.resize(n);
  for (std::size_t p = 0; p < n; ++p)
  {
    if (ws.sideA.pixelClass[p] == PixelClass::HoleFilled ||
        ws.sideB.pixelClass[p] == PixelClass::HoleFilled)
    {
      out[p] = 255;
      continue;
    }
    int diff = 0;
    for (int c = 0; c < 3; ++c)
      diff = std::max(diff, std::abs(static_cast<int>(ws.sideA.rgb[3 * p + c]) -
                                     static_cast<int>(ws.sideB.rgb[3 * p + c])));
    out[p] = static_cast<std::uint8_t>(diff);
  }
}

SourceFields sourceFields(const SplatSet& set, std::int32_t splat, double t)
{
  SourceFields f;
  if (splat < 0 || static_cast<std::size_t>(splat) >= set.splats.size())
    return f;
  const std::size_t k = static_cast<std::size_t>(splat);
  const bool sideB = k >= set.pixelCount();
  const double s = sideB ? 1.0 - t : t;
  f.objectId = set.objectId[k];
  f.imageOrder = set.imageOrder[k];
  f.termination = set.termination[k];
  f.pathLength = set.pathLength[k] + s * static_cast<double>(set.splats[k].dLength);
  return f;
}

void sourceFieldsOf(const SplatSet& set, const InterpolatedFrame& frame, std::int32_t* objectId,
                    std::int32_t* imageOrder, std::int32_t* termination, double* pathLength)
{
  const std::int64_t n = static_cast<std::int64_t>(frame.width) * frame.height;
  const double t = frame.t;
#pragma omp parallel for schedule(static) if (static_cast <std::size_t>(n) > kParallelPixels)
  for (std::int64_t p = 0; p < n; ++p)
  {
    const SourceFields f = sourceFields(set, frame.source[static_cast<std::size_t>(p)], t);
    objectId[p] = f.objectId;
    imageOrder[p] = f.imageOrder;
    termination[p] = f.termination;
    pathLength[p] = f.pathLength;
  }
}

bool pushPullFill(int width, int height, int channels, float* values, const float* weights,
                  std::vector<float>* scratch)
{
  if (width <= 0 || height <= 0 || channels <= 0)
    return false;
  // Level sizes, then one buffer: per level, `channels` values and one weight per pixel.
  struct Level
  {
    int w, h;
    std::size_t offset; ///< of its values; the weights follow them
  };
  std::vector<Level> levels;
  std::size_t total = 0;
  for (int w = width, h = height;;)
  {
    levels.push_back({ w, h, total });
    total += static_cast<std::size_t>(w) * h * (channels + 1);
    if (w == 1 && h == 1)
      break;
    w = (w + 1) / 2;
    h = (h + 1) / 2;
  }
  std::vector<float> local;
  std::vector<float>& buf = scratch ? *scratch : local;
  if (buf.size() < total)
    buf.resize(total);
  auto val = [&](const Level& l, int x, int y)
  { return &buf[l.offset + (static_cast<std::size_t>(y) * l.w + x) * channels]; };
  auto wgt = [&](const Level& l, int x, int y) -> float&
  {
    return buf[l.offset + static_cast<std::size_t>(l.w) * l.h * channels +
               static_cast<std::size_t>(y) * l.w + x];
  };
  // Threads only pay off on large levels (a parallel region costs a time slice on a busy machine).
  const long parallelPixels = 1L << 16;
  {
    const Level& l0 = levels[0];
#pragma omp parallel for schedule(static) if (static_cast <long>(width) * height > parallelPixels)
    for (int y = 0; y < height; ++y)
      for (int x = 0; x < width; ++x)
      {
        const std::size_t p = static_cast<std::size_t>(y) * width + x;
        const bool known = weights[p] > 0;
        wgt(l0, x, y) = known ? 1.0f : 0.0f;
        float* v = val(l0, x, y);
        for (int c = 0; c < channels; ++c)
          v[c] = known ? values[p * channels + c] : 0.0f;
      }
  }
  // Push: each level the weighted mean of the four below, its weight their sum capped at 1.
  for (std::size_t k = 1; k < levels.size(); ++k)
  {
    const Level &lo = levels[k - 1], &hi = levels[k];
#pragma omp parallel for schedule(static) if (static_cast <long>(hi.w) * hi.h > parallelPixels)
    for (int y = 0; y < hi.h; ++y)
      for (int x = 0; x < hi.w; ++x)
      {
        float* v = val(hi, x, y);
        float wsum = 0;
        for (int c = 0; c < channels; ++c)
          v[c] = 0;
        for (int dy = 0; dy < 2; ++dy)
          for (int dx = 0; dx < 2; ++dx)
          {
            const int cx = 2 * x + dx, cy = 2 * y + dy;
            if (cx >= lo.w || cy >= lo.h)
              continue;
            const float w = wgt(lo, cx, cy);
            const float* cv = val(lo, cx, cy);
            for (int c = 0; c < channels; ++c)
              v[c] += w * cv[c];
            wsum += w;
          }
        if (wsum > 0)
          for (int c = 0; c < channels; ++c)
            v[c] /= wsum;
        wgt(hi, x, y) = std::min(1.0f, wsum);
      }
  }
  if (wgt(levels.back(), 0, 0) <= 0)
    return false;
  // Pull: from the top down, each pixel's missing weight is made up by the level above,
  // upsampled bilinearly.
  for (std::size_t k = levels.size() - 1; k-- > 0;)
  {
    const Level &lo = levels[k], &hi = levels[k + 1];
#pragma omp parallel for schedule(static) if (static_cast <long>(lo.w) * lo.h > parallelPixels)
    for (int y = 0; y < lo.h; ++y)
      for (int x = 0; x < lo.w; ++x)
      {
        float& w = wgt(lo, x, y);
        if (w >= 1.0f)
          continue;
        const float sx = std::clamp(0.5f * (x + 0.5f) - 0.5f, 0.0f, static_cast<float>(hi.w - 1));
        const float sy = std::clamp(0.5f * (y + 0.5f) - 0.5f, 0.0f, static_cast<float>(hi.h - 1));
        const int x0 = static_cast<int>(sx), y0 = static_cast<int>(sy);
        const int x1 = std::min(x0 + 1, hi.w - 1), y1 = std::min(y0 + 1, hi.h - 1);
        const float ax = sx - x0, ay = sy - y0;
        float* v = val(lo, x, y);
        const float *v00 = val(hi, x0, y0), *v10 = val(hi, x1, y0), *v01 = val(hi, x0, y1),
                    *v11 = val(hi, x1, y1);
        for (int c = 0; c < channels; ++c)
        {
          const float up =
            (1 - ay) * ((1 - ax) * v00[c] + ax * v10[c]) + ay * ((1 - ax) * v01[c] + ax * v11[c]);
          v[c] = w * v[c] + (1 - w) * up;
        }
        w = 1.0f;
      }
  }
  const Level& l0 = levels[0];
#pragma omp parallel for schedule(static) if (static_cast <long>(width) * height > parallelPixels)
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x)
    {
      const std::size_t p = static_cast<std::size_t>(y) * width + x;
      if (weights[p] > 0)
        continue;
      const float* v = val(l0, x, y);
      for (int c = 0; c < channels; ++c)
        values[p * channels + c] = v[c];
    }
  return true;
}
}
