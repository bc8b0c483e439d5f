#include "FrameInterpolation.h"

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

namespace
{
/// Splats whose footprint deviates from the identity by at most this (any entry of s·(D − I))
/// are drawn with plain bilinear weights: neighbours then lie at most 1.25 px apart, which the
/// bilinear kernels (support ±1 px) still cover without gaps.
constexpr float kBilinearDeviation = 0.25f;
/// A splat counts for visibility where its weight reaches this; lighter touches (its fringe)
/// blend but never hide what lies behind.
constexpr float kVisibleWeight = 0.2f;
/// Frames smaller than this are rendered on one thread: a parallel region costs more than it
/// saves there (a time slice, on a busy machine).
constexpr std::size_t kParallelPixels = 16384;
/// How many list entries ahead of the one being drawn its splat is prefetched.
constexpr std::int64_t kPrefetchAhead = 16;

bool sameImage(SampleKind ka, const PixelSample& a, SampleKind kb, const PixelSample& b)
{
  if (ka != kb)
    return false;
  if (ka == SampleKind::Shadow)
    return true;
  return (ka == SampleKind::Surface || ka == SampleKind::Escaped) && a.objectId == b.objectId &&
         a.imageOrder == b.imageOrder;
}

void buildSide(const FrameSamples& self, const FrameSamples& other,
               const std::vector<PixelMatch>& matches, std::size_t offset,
               const InterpolationOptions& opt, SplatSet& out)
{
  const int W = self.width, H = self.height;
  const std::size_t n = self.pixels.size();
  std::vector<SampleKind> kind(n), otherKind(n);
  for (std::size_t p = 0; p < n; ++p)
  {
    kind[p] = kindOf(self.pixels[p]);
    otherKind[p] = kindOf(other.pixels[p]);
  }
  for (std::size_t p = 0; p < n; ++p)
  {
    const PixelSample& s = self.pixels[p];
    const PixelMatch& m = matches[p];
    const int i = static_cast<int>(p % W), j = static_cast<int>(p / W);
    SplatSet::Splat& sp = out.splats[offset + p];
    sp.dx = m.x - static_cast<float>(i);
    sp.dy = m.y - static_cast<float>(j);
    sp.length = static_cast<float>(s.pathLength);
    sp.dLength = 0;
    for (int c = 0; c < 3; ++c)
      sp.color[c] = sp.other[c] = s.rgb[c];
    sp.cls = static_cast<std::uint8_t>(m.kind == MatchKind::Matched     ? PixelClass::Matched
                                       : m.kind == MatchKind::Ambiguous ? PixelClass::Ambiguous
                                                                        : PixelClass::OneSided);
    const bool surface = kind[p] == SampleKind::Surface;
    sp.layer =
      surface ? static_cast<std::uint8_t>(std::clamp(s.imageOrder, 0, 14)) : SplatSet::kBackdrop;

    if (m.kind == MatchKind::Matched)
    {
      // The other frame's colour and path length at the position: bilinear over its pixels of
      // the same image there, else the partner's.
      const int x0 = static_cast<int>(std::floor(m.x)), y0 = static_cast<int>(std::floor(m.y));
      const float ax = m.x - static_cast<float>(x0), ay = m.y - static_cast<float>(y0);
      double sum[4] = { 0, 0, 0, 0 }, wsum = 0;
      for (int dj = 0; dj < 2; ++dj)
        for (int di = 0; di < 2; ++di)
        {
          const int x = x0 + di, y = y0 + dj;
          const float w = (di ? ax : 1 - ax) * (dj ? ay : 1 - ay);
          if (x < 0 || x >= W || y < 0 || y >= H || w <= 0)
            continue;
          const std::size_t q = static_cast<std::size_t>(y) * W + x;
          if (!sameImage(kind[p], s, otherKind[q], other.pixels[q]))
            continue;
          for (int c = 0; c < 3; ++c)
            sum[c] += w * other.pixels[q].rgb[c];
          sum[3] += w * other.pixels[q].pathLength;
          wsum += w;
        }
      if (wsum <= 0 && m.partner >= 0)
      {
        const PixelSample& q = other.pixels[static_cast<std::size_t>(m.partner)];
        for (int c = 0; c < 3; ++c)
          sum[c] = q.rgb[c];
        sum[3] = q.pathLength;
        wsum = 1;
      }
      if (wsum > 0)
      {
        for (int c = 0; c < 3; ++c)
          sp.other[c] =
            static_cast<std::uint8_t>(std::lround(std::clamp(sum[c] / wsum, 0.0, 255.0)));
        sp.dLength = static_cast<float>(sum[3] / wsum - s.pathLength);
      }
    }

    // Splats of one surface within this margin of each other blend: the relative tolerance, plus
    // how fast the path length changes to the next pixel of the same image.
    double slope = 0;
    if (surface)
    {
      const int di[4] = { -1, 1, 0, 0 }, dj[4] = { 0, 0, -1, 1 };
      for (int k = 0; k < 4; ++k)
      {
        const int x = i + di[k], y = j + dj[k];
        if (x < 0 || x >= W || y < 0 || y >= H)
          continue;
        const std::size_t q = static_cast<std::size_t>(y) * W + x;
        if (sameImage(kind[p], s, kind[q], self.pixels[q]))
          slope = std::max(slope, std::abs(self.pixels[q].pathLength - s.pathLength));
      }
      slope = std::min(slope, 0.25 * std::abs(s.pathLength));
    }
    sp.margin = static_cast<float>(opt.depthTolerance * std::abs(s.pathLength) + slope);

    // Only matched pixels know how their neighbourhood maps; a pixel seen in one frame keeps a
    // one-pixel footprint (its motion is a guess: spreading it would smear the guess).
    float deviation = 0;
    for (int k = 0; k < 4; ++k)
      deviation = std::max(deviation, std::abs(m.jacobian[k] - ((k == 0 || k == 3) ? 1.0f : 0.0f)));
    sp.footprint = -1;
    if (m.kind == MatchKind::Matched && deviation > kBilinearDeviation && std::isfinite(deviation))
    {
      sp.footprint = static_cast<std::int32_t>(out.jacobians.size());
      out.jacobians.push_back(m.jacobian);
      out.jacobianDeviation.push_back(deviation);
    }

    out.objectId[offset + p] = s.objectId;
    out.imageOrder[offset + p] = s.imageOrder;
    out.termination[offset + p] = static_cast<std::uint8_t>(s.termination);
    out.pathLength[offset + p] = s.pathLength;
  }
}

}

SplatSet buildSplats(const FrameSamples& a, const FrameSamples& b, const Correspondence& c,
                     const InterpolationOptions& options)
{
  if (a.width != b.width || a.height != b.height || c.width != a.width || c.height != a.height ||
      c.aToB.size() != a.pixels.size() || c.bToA.size() != b.pixels.size() ||
      a.pixels.size() != static_cast<std::size_t>(a.width) * a.height)
    throw InvalidParameter("buildSplats: the frames and their correspondence do not fit together");
  if (!(options.maxMagnification >= 1.0f) || !(options.depthTolerance >= 0.0f) ||
      options.bandRows < 0)
    throw InvalidParameter("buildSplats: invalid options");
  SplatSet set;
  set.width = a.width;
  set.height = a.height;
  set.options = options;
  const std::size_t n = a.pixels.size();
  set.splats.resize(2 * n);
  set.objectId.resize(2 * n);
  set.imageOrder.resize(2 * n);
  set.termination.resize(2 * n);
  set.pathLength.resize(2 * n);
  buildSide(a, b, c.aToB, 0, options, set);
  buildSide(b, a, c.bToA, n, options, set);
  // Pairs that match each other.
  const int W = a.width, H = a.height;
  auto markMutual =
    [&](const std::vector<PixelMatch>& from, const std::vector<PixelMatch>& to, std::size_t offset)
  {
    for (std::size_t p = 0; p < n; ++p)
    {
      const PixelMatch& m = from[p];
      if (m.kind != MatchKind::Matched)
        continue;
      const long qi = std::lround(m.x), qj = std::lround(m.y);
      if (qi < 0 || qi >= W || qj < 0 || qj >= H)
        continue;
      const PixelMatch& back = to[static_cast<std::size_t>(qj) * W + static_cast<std::size_t>(qi)];
      if (back.kind == MatchKind::Matched && std::abs(back.x - static_cast<float>(p % W)) <= 1.0f &&
          std::abs(back.y - static_cast<float>(p / W)) <= 1.0f)
        set.splats[offset + p].cls |= SplatSet::kMutual;
    }
  };
  markMutual(c.aToB, c.bToA, 0);
  markMutual(c.bToA, c.aToB, n);

  // Layers must never overlap in key: the stride exceeds every path length a splat can reach.
  float longest = 0;
  for (const SplatSet::Splat& s : set.splats)
    longest = std::max({ longest, std::abs(s.length), std::abs(s.length + s.dLength) });
  set.layerStride = 2.0f * longest + 1.0f;

  // Bands: every splat is listed in each band of rows it can reach at some t (its path from one
  // end to the other, widened by its largest footprint).
  const int rows = options.bandRows > 0 ? options.bandRows : std::max(16, H / 16);
  set.bandRows = rows;
  const int bands = (H + rows - 1) / rows;
  constexpr int K = SplatSet::kSegments;
  const std::size_t lists = static_cast<std::size_t>(bands) * (K + 1) * 4;
  const float maxExtent = std::sqrt(2.0f) * options.maxMagnification;
  auto group = [&](std::size_t k)
  { return (k >= n ? 2 : 0) + ((set.splats[k].cls & SplatSet::kMutual) ? 0 : 1); };
  // Calls visit(list) for every list splat k belongs in.
  auto place = [&](std::size_t k, const auto& visit)
  {
    const SplatSet::Splat& s = set.splats[k];
    const std::size_t p = k % n;
    const float x = static_cast<float>(p % W), y = static_cast<float>(p / W);
    float ex = 1, ey = 1;
    if (s.footprint >= 0)
    {
      const auto& d = set.jacobians[static_cast<std::size_t>(s.footprint)];
      ex = std::min(maxExtent, std::max(std::sqrt(2.0f), std::abs(d[0]) + std::abs(d[1])));
      ey = std::min(maxExtent, std::max(std::sqrt(2.0f), std::abs(d[2]) + std::abs(d[3])));
    }
    const float xlo = std::min(x, x + s.dx) - ex, xhi = std::max(x, x + s.dx) + ex;
    auto bandsOf = [&](float y0, float y1, int& b0, int& b1)
    {
      const float lo = std::min(y0, y1) - ey, hi = std::max(y0, y1) + ey;
      if (!(xhi >= 0 && xlo <= W - 1 && hi >= 0 && lo <= H - 1))
        return false; // outside the frame
      b0 = static_cast<int>(std::max(0.0f, lo)) / rows;
      b1 = static_cast<int>(std::min(static_cast<float>(H - 1), hi)) / rows;
      return true;
    };
    int b0 = 0, b1 = -1;
    if (!bandsOf(y, y + s.dy, b0, b1))
      return;
    const int g = group(k);
    if (b1 - b0 <= 1)
    {
      for (int b = b0; b <= b1; ++b)
        visit(set.listIndex(b, 0, g), b);
      return;
    }
    // A splat of side B moves with s = 1 − t: slice k of t is slice K − 1 − k of its path.
    const bool sideB = k >= n;
    for (int slice = 0; slice < K; ++slice)
    {
      const float s0 = static_cast<float>(sideB ? K - 1 - slice : slice) / K;
      const float s1 = s0 + 1.0f / K;
      if (bandsOf(y + s0 * s.dy, y + s1 * s.dy, b0, b1))
        for (int b = b0; b <= b1; ++b)
          visit(set.listIndex(b, 1 + slice, g), b);
    }
  };
  std::vector<std::int64_t> count(lists + 1, 0);
  for (std::size_t k = 0; k < 2 * n; ++k)
    place(k, [&](std::size_t list, int) { ++count[list + 1]; });
  for (std::size_t l = 0; l < lists; ++l)
    count[l + 1] += count[l];
  set.bandStart = count;
  set.bandSplats.resize(static_cast<std::size_t>(count.back()));
  set.bandReach.resize(set.bandSplats.size());
  std::vector<std::int64_t> fill(count.begin(), count.end() - 1);
  // When (in its own s) a splat may touch band b: y(s) = y + s·dy within the band's rows widened
  // by its largest reach and a pixel to spare, in 255ths of s rounded outwards, and a 255th more.
  auto reach = [&](std::size_t k, int b)
  {
    const SplatSet::Splat& sp = set.splats[k];
    const float y = static_cast<float>((k % n) / W);
    const float spare = (sp.footprint >= 0 ? std::max(1.0f, maxExtent) : 1.0f) + 1.0f;
    const float lo = static_cast<float>(b * rows) - spare,
                hi = static_cast<float>(std::min(H, (b + 1) * rows)) + spare;
    float sLo = 0, sHi = 1;
    if (std::abs(sp.dy) > 1e-6f)
    {
      const float a0 = (lo - y) / sp.dy, a1 = (hi - y) / sp.dy;
      sLo = std::max(0.0f, std::min(a0, a1));
      sHi = std::min(1.0f, std::max(a0, a1));
    }
    const int qLo = std::clamp(static_cast<int>(std::floor(sLo * 255.0f)) - 1, 0, 255);
    const int qHi = std::clamp(static_cast<int>(std::ceil(sHi * 255.0f)) + 1, 0, 255);
    return std::array<std::uint8_t, 2>{ { static_cast<std::uint8_t>(qLo),
                                          static_cast<std::uint8_t>(qHi) } };
  };
  for (std::size_t k = 0; k < 2 * n; ++k)
    place(k,
          [&](std::size_t list, int b)
          {
            const std::size_t e = static_cast<std::size_t>(fill[list]++);
            set.bandSplats[e] = static_cast<std::int32_t>(k);
            set.bandReach[e] = reach(k, b);
          });
  return set;
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
}

namespace
{
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
}

void renderFrame(const SplatSet& set, double tIn, InterpolatedFrame& out,
                 InterpolationWorkspace& ws, SplatSides sides)
{
  requireFinite(tIn, "interpolation time");
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
    // The ends are the traced frames themselves.
    const std::size_t offset = t == 0.0 ? 0 : n;
    for (std::size_t p = 0; p < n; ++p)
    {
      const SplatSet::Splat& sp = set.splats[offset + p];
      std::copy(sp.color, sp.color + 3, &out.rgb[3 * p]);
      out.pixelClass[p] = static_cast<PixelClass>(sp.cls & ~SplatSet::kMutual);
      out.source[p] = static_cast<std::int32_t>(offset + p);
    }
    return;
  }
  // Which groups of splats this frame draws, and at what weight: a mutual pair from the frame
  // nearer in t at full weight, every other splat from its own frame at (1 − t) or t.
  const float tf = static_cast<float>(t);
  bool drawGroup[4];
  float groupWeight[4];
  if (sides == SplatSides::Both)
  {
    drawGroup[0] = tf < 0.5f;
    drawGroup[1] = tf < 1.0f;
    drawGroup[2] = tf >= 0.5f;
    drawGroup[3] = tf > 0.0f;
    groupWeight[0] = groupWeight[2] = 1.0f;
    groupWeight[1] = 1.0f - tf;
    groupWeight[3] = tf;
  }
  else
  {
    const bool a = sides == SplatSides::AOnly;
    drawGroup[0] = drawGroup[1] = a;
    drawGroup[2] = drawGroup[3] = !a;
    std::fill(groupWeight, groupWeight + 4, 1.0f);
  }
  const int rows = set.bandRows;
  const int bands = (H + rows - 1) / rows;
  const int slice =
    1 + std::min(SplatSet::kSegments - 1, static_cast<int>(t * SplatSet::kSegments));
  const int threads = omp_get_max_threads();
  if (static_cast<int>(ws.bands.size()) < threads)
    ws.bands.resize(static_cast<std::size_t>(threads));
  const float maxMag = set.options.maxMagnification;
  // No footprint reaches further from its centre than this (its singular values are clamped;
  // with a hair to spare for the rounding of the clamped map).
  const float maxExtent = 1.0001f * std::sqrt(2.0f) * maxMag;
  // Accumulators of a band: its rows plus a guard row above and below and a guard column on
  // each side, so that the four taps of a bilinear splat need no bounds checks.
  const int stride = W + 2;
  std::int64_t holes = 0;

  // The bands with the most splats to draw first, so that the threads finish together (each
  // band's pixels are what they are whichever thread draws it, and whenever).
  std::vector<int>& order = ws.bandOrder;
  std::vector<std::int64_t>& work = ws.bandWork;
  order.resize(static_cast<std::size_t>(bands));
  if (ws.bandHoles.size() < static_cast<std::size_t>(bands))
    ws.bandHoles.resize(static_cast<std::size_t>(bands));
  work.assign(static_cast<std::size_t>(bands), 0);
  for (int b = 0; b < bands; ++b)
  {
    order[static_cast<std::size_t>(b)] = b;
    for (int gs = 0; gs < 8; ++gs)
      if (drawGroup[gs % 4])
      {
        const std::size_t list = set.listIndex(b, gs < 4 ? 0 : slice, gs % 4);
        work[static_cast<std::size_t>(b)] += set.bandStart[list + 1] - set.bandStart[list];
      }
  }
  std::stable_sort(order.begin(), order.end(),
                   [&](int x, int y) {
                     return work[static_cast<std::size_t>(x)] > work[static_cast<std::size_t>(y)];
                   });

  const bool emptied = ws.bandsEmpty;
  ws.bandsEmpty = false; // until this render has emptied them again
  // The arrays as plain pointers and the splat's fields as locals: the deposits store bytes,
  // which may alias anything, and would otherwise have every one of them loaded again after
  // each touch.
  const SplatSet::Splat* const splats = set.splats.data();
  const std::int32_t* const bandSplats = set.bandSplats.data();
  const std::array<std::uint8_t, 2>* const bandReach = set.bandReach.data();
  const std::int64_t* const bandStart = set.bandStart.data();
  const float* const jacobianDeviation = set.jacobianDeviation.data();
  const float layerStride = set.layerStride;
  std::uint8_t* const rgbOut = out.rgb.data();
  PixelClass* const classOut = out.pixelClass.data();
  std::int32_t* const sourceOut = out.source.data();
#pragma omp parallel reduction(+ : holes) if (n > kParallelPixels)
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
      for (int gs = 0; gs < 8; ++gs)
      {
        const int g = gs % 4;
        if (!drawGroup[g])
          continue;
        const bool sideB = g >= 2;
        const float sideWeight = groupWeight[g];
        const float s = sideB ? 1.0f - tf : tf;
        // One side alone shows its own frame's colours: what each frame says is there.
        const __m128 blend = _mm_set1_ps(sides == SplatSides::Both ? s : 0.0f);
        const std::size_t list = set.listIndex(b, gs < 4 ? 0 : slice, g);
        std::size_t rowStart = std::numeric_limits<std::size_t>::max() / 2;
        int row = 0;
        const std::int64_t end = bandStart[list + 1];
        // s in 255ths, rounded down and up: s · 255 < lo ⇔ below < lo, s · 255 > hi ⇔ above > hi.
        const int below = static_cast<int>(std::floor(s * 255.0f)),
                  above = static_cast<int>(std::ceil(s * 255.0f));
        for (std::int64_t e = bandStart[list]; e < end; ++e)
        {
          // Turned away unread when it cannot reach this band at this t.
          const auto& r = bandReach[e];
          if (below < r[0] || above > r[1])
            continue;
          const std::int32_t index = bandSplats[e];
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
          // Many listed splats lie outside this band at this t (those listed in two bands, or
          // for a whole slice of t): they are turned away before their key and colour are made.
          const bool bilinear =
            sp.footprint < 0 || s * jacobianDeviation[sp.footprint] <= kBilinearDeviation;
          const float fx = std::floor(x), fy = std::floor(y);
          if (bilinear ? !(fx >= -1.0f && fx < static_cast<float>(W) &&
                           fy >= static_cast<float>(r0 - 1) && fy < static_cast<float>(r1))
                       : !(y + maxExtent >= static_cast<float>(r0) &&
                           y - maxExtent < static_cast<float>(r1)))
            continue; // no tap inside the band (NaN positions end here too)
          const float key = static_cast<float>(sp.layer) * layerStride + sp.length + s * sp.dLength;
          const float margin = sp.margin;
          const std::uint8_t cls = sp.cls;
          // Colour (r, g, b, 1) at t: own + blend · (other − own).
          const __m128 own = colorOf(sp.color), other = colorOf(sp.other);
          const Color4 color = _mm_add_ps(own, _mm_mul_ps(blend, _mm_sub_ps(other, own)));

          if (bilinear)
          {
            const float ax = x - fx, ay = y - fy;
            Accumulator* a =
              origin + static_cast<std::ptrdiff_t>(fy) * stride + static_cast<std::ptrdiff_t>(fx);
            const float w00 = (1 - ax) * (1 - ay), w10 = ax * (1 - ay), w01 = (1 - ax) * ay,
                        w11 = ax * ay;
            // Usually all four taps touch: one test for them (the same deposits, in order).
            if ((w00 > 0) & (w10 > 0) & (w01 > 0) & (w11 > 0))
            {
              deposit(a[0], w00, key, margin, color, sideWeight, index, cls);
              deposit(a[1], w10, key, margin, color, sideWeight, index, cls);
              deposit(a[stride], w01, key, margin, color, sideWeight, index, cls);
              deposit(a[stride + 1], w11, key, margin, color, sideWeight, index, cls);
              continue;
            }
            if (w00 > 0)
              deposit(a[0], w00, key, margin, color, sideWeight, index, cls);
            if (w10 > 0)
              deposit(a[1], w10, key, margin, color, sideWeight, index, cls);
            if (w01 > 0)
              deposit(a[stride], w01, key, margin, color, sideWeight, index, cls);
            if (w11 > 0)
              deposit(a[stride + 1], w11, key, margin, color, sideWeight, index, cls);
            continue;
          }
          const auto& d = set.jacobians[static_cast<std::size_t>(sp.footprint)];
          const float m[4] = { 1.0f + s * (d[0] - 1.0f), s * d[1], s * d[2],
                               1.0f + s * (d[3] - 1.0f) };
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
              const float w =
                std::max(0.0f, 1.0f - std::abs(u)) * std::max(0.0f, 1.0f - std::abs(v));
              if (w > 0.0f)
                deposit(line[px], w, key, margin, color, sideWeight, index, cls);
            }
          }
        }
      }

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
          const __m128i rounded = _mm_cvttps_epi32(
            _mm_add_ps(_mm_min_ps(_mm_max_ps(mean, _mm_setzero_ps()), _mm_set1_ps(255.0f)),
                       _mm_set1_ps(0.5f)));
          alignas(16) std::int32_t channels[4];
          _mm_store_si128(reinterpret_cast<__m128i*>(channels), rounded);
          rgbOut[3 * p] = static_cast<std::uint8_t>(channels[0]);
          rgbOut[3 * p + 1] = static_cast<std::uint8_t>(channels[1]);
          rgbOut[3 * p + 2] = static_cast<std::uint8_t>(channels[2]);
          sourceOut[p] = a.best;
          classOut[p] = static_cast<PixelClass>(a.cls & ~SplatSet::kMutual);
        }
      }
    }
  }
  ws.bandsEmpty = true;
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
