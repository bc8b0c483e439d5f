// buildSplats: the splats of both frames from their correspondence, and the lists of the
// splats each band of rows may need.
#include "FrameInterpolation.h"

#include "SplatKernel.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <limits>

namespace asrt
{
namespace
{
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
    out.hitRadius[offset + p] = s.termination == Termination::HitObject
                                  ? static_cast<float>(s.point.norm())
                                  : std::numeric_limits<float>::infinity();
  }
}

/// Flags the splats of one side (from `offset`) whose pixel and partner match each other.
void markMutual(const std::vector<PixelMatch>& from, const std::vector<PixelMatch>& to,
                std::size_t offset, SplatSet& set)
{
  const int W = set.width, H = set.height;
  const std::size_t n = set.pixelCount();
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
}

/// Where a splat set's splats go in its bands of rows.
struct BandListing
{
  const SplatSet& set;
  std::size_t n;
  int W, H, rows;
  float maxExtent; ///< the reach of the largest footprint

  int group(std::size_t k) const
  {
    return (k >= this->n ? 2 : 0) + ((this->set.splats[k].cls & SplatSet::kMutual) ? 0 : 1);
  }

  /// Calls visit(list, band) for every list splat k belongs in: each band of rows it can reach
  /// at some t (its path from one end to the other, widened by its largest footprint).
  template<class Visit>
  void place(std::size_t k, const Visit& visit) const
  {
    constexpr int K = SplatSet::kSegments;
    const int W = this->W, H = this->H, rows = this->rows;
    const SplatSet::Splat& s = this->set.splats[k];
    const std::size_t p = k % this->n;
    const float x = static_cast<float>(p % W), y = static_cast<float>(p / W);
    float ex = kBilinearReach, ey = kBilinearReach;
    if (s.footprint >= 0)
    {
      const auto& d = this->set.jacobians[static_cast<std::size_t>(s.footprint)];
      ex = std::min(this->maxExtent, std::max(std::sqrt(2.0f), std::abs(d[0]) + std::abs(d[1])));
      ey = std::min(this->maxExtent, std::max(std::sqrt(2.0f), std::abs(d[2]) + std::abs(d[3])));
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
    const int g = this->group(k);
    if (b1 - b0 <= 1)
    {
      for (int b = b0; b <= b1; ++b)
        visit(this->set.listIndex(b, 0, g), b);
      return;
    }
    // A splat of side B moves with s = 1 − t: slice k of t is slice K − 1 − k of its path.
    const bool sideB = k >= this->n;
    for (int slice = 0; slice < K; ++slice)
    {
      const float s0 = static_cast<float>(sideB ? K - 1 - slice : slice) / K;
      const float s1 = s0 + 1.0f / K;
      if (bandsOf(y + s0 * s.dy, y + s1 * s.dy, b0, b1))
        for (int b = b0; b <= b1; ++b)
          visit(this->set.listIndex(b, 1 + slice, g), b);
    }
  }

  /// When (in its own s) splat k may touch band b: y(s) = y + s·dy within the band's rows
  /// widened by its reach and kBandReachSpare, in 255ths of s rounded outwards, and a 255th more.
  std::array<std::uint8_t, 2> reach(std::size_t k, int b) const
  {
    const SplatSet::Splat& sp = this->set.splats[k];
    const float y = static_cast<float>((k % this->n) / this->W);
    const float spare =
      (sp.footprint >= 0 ? std::max(kBilinearReach, this->maxExtent) : kBilinearReach) +
      kBandReachSpare;
    const float lo = static_cast<float>(b * this->rows) - spare,
                hi = static_cast<float>(std::min(this->H, (b + 1) * this->rows)) + spare;
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
  }
};

/// Fills the set's band lists (bandStart, bandSplats, bandReach) for bands of `rows` rows.
void listInBands(int rows, SplatSet& set)
{
  set.bandRows = rows;
  const std::size_t n = set.pixelCount();
  const int bands = (set.height + rows - 1) / rows;
  const std::size_t lists = static_cast<std::size_t>(bands) * (SplatSet::kSegments + 1) * 4;
  const float maxExtent = footprintReach(set.options.maxMagnification, kListingReachMargin);
  const BandListing listing{ set, n, set.width, set.height, rows, maxExtent };
  std::vector<std::int64_t> count(lists + 1, 0);
  for (std::size_t k = 0; k < 2 * n; ++k)
    listing.place(k, [&](std::size_t list, int) { ++count[list + 1]; });
  for (std::size_t l = 0; l < lists; ++l)
    count[l + 1] += count[l];
  set.bandStart = count;
  set.bandSplats.resize(static_cast<std::size_t>(count.back()));
  set.bandReach.resize(set.bandSplats.size());
  std::vector<std::int64_t> fill(count.begin(), count.end() - 1);
  for (std::size_t k = 0; k < 2 * n; ++k)
    listing.place(k,
                  [&](std::size_t list, int b)
                  {
                    const std::size_t e = static_cast<std::size_t>(fill[list]++);
                    set.bandSplats[e] = static_cast<std::int32_t>(k);
                    set.bandReach[e] = listing.reach(k, b);
                  });
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
  set.hitRadius.resize(2 * n);
  buildSide(a, b, c.aToB, 0, options, set);
  buildSide(b, a, c.bToA, n, options, set);
  markMutual(c.aToB, c.bToA, 0, set);
  markMutual(c.bToA, c.aToB, n, set);

  // Layers must never overlap in key: the stride exceeds every path length a splat can reach.
  float longest = 0;
  for (const SplatSet::Splat& s : set.splats)
    longest = std::max({ longest, std::abs(s.length), std::abs(s.length + s.dLength) });
  set.layerStride = 2.0f * longest + 1.0f;

  listInBands(options.bandRows > 0 ? options.bandRows : std::max(16, a.height / 16), set);
  return set;
}
}
