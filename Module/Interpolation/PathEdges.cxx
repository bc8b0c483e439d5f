#include "PathEdges.h"

#include "Spacetime.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <iterator>
#include <limits>
#include <map>
#include <numeric>

namespace asrt
{
namespace
{
/// The vertical view angle (degrees) the keys' rays were aimed with: from the directions, in the
/// observer's frame (right, up, forward), of two rows about the middle of the middle column.
double viewAngleOf(const std::vector<RayRecord>& records, int width, int height)
{
  if (height < 2)
    return 30.0;
  const std::size_t i = static_cast<std::size_t>(width / 2);
  const std::size_t j = static_cast<std::size_t>(height / 2);
  const Vec3& d0 = records[(j - 1) * static_cast<std::size_t>(width) + i].direction;
  const Vec3& d1 = records[j * static_cast<std::size_t>(width) + i].direction;
  if (!(d0.z() > 0 && d1.z() > 0))
    return 30.0;
  const double pixel = d1.y() / d1.z() - d0.y() / d0.z(); // 2 tan(angle / 2) / height
  const double angle = 2.0 * std::atan(0.5 * pixel * height) * 180.0 / M_PI;
  return angle > 0 && angle < 180 ? angle : 30.0;
}

/// Where no point can be followed: a lost ray.
bool followable(const RayRecord& r)
{
  return r.termination == Termination::Escaped || r.termination == Termination::Captured ||
         r.termination == Termination::HitObject;
}

/// A scene point of an inner key, moved to t.
struct Mover
{
  double x[2] = { 0, 0 };         ///< at t, through every key it is matched in
  double lin[2] = { 0, 0 };       ///< at t, through the inner pair alone
  double inv[4] = { 1, 0, 0, 1 }; ///< inverse of its pixel's map to t, row-major
  double length = 0;              ///< path length: the shorter covers the longer
  std::uint8_t reach = 0;         ///< cells from its own that the spots it covers lie within
  const RayRecord* record = nullptr;
  std::uint8_t side = 0; ///< 0: key a's, 1: key a + 1's
  bool usable = false;
  /// Its scene point lies inside the hole's outer horizon at t (PathEdges.h, The horizon).
  bool swallowed = false;
};

/// Whether the spot at offset d within a mover's source pixel still lies on its object: the
/// surface's v, carried there by the record's Jacobian, stays within [0, 1] (the object's
/// extent; u may wrap round). A point by an object's rim covers only the part of its square
/// on the object's side of the rim, which places the rim within the pixel.
bool onSurface(const Mover& m, const double* d)
{
  const RayRecord& r = *m.record;
  if (r.objectId < 0 || !std::isfinite(r.dvdi + r.dvdj))
    return true;
  const double v = r.v + r.dvdi * d[0] + r.dvdj * d[1];
  return v >= 0.0 && v <= 1.0;
}

/// Farthest a mover's square reaches from its centre along either axis, in pixels: movers
/// stretched wider are left to the others (the photon ring between keys far apart).
constexpr int kReach = 3;
/// Slack on a square's edges, so that neighbouring squares leave no cracks to rounding.
constexpr double kSeam = 1e-6;
/// Farthest outside every square that a spot still takes the nearest one (a hairline gap
/// between squares that do not quite tile where the motion bends); beyond it, nothing covers it.
constexpr double kGap = 0.25;

class EdgeMover
{
public:
  EdgeMover(const std::vector<PathKey>& keys, std::size_t a, double t, int width, int height,
            const PointIndexFactory& index, PathMatchCache* cache, const SpacetimeAlongPath& along)
    : width_(width)
    , height_(height)
    , atT_(along ? along(t) : nullptr)
    , horizonAtT_(atT_ ? atT_->outerHorizon() : 0.0)
  {
    // Where the hole grows between the inner keys, the horizon at t places what it swallows
    // (PathEdges.h, The horizon), and the rim is not hedged.
    if (atT_)
    {
      const std::shared_ptr<const Spacetime> before = along(keys[a].s),
                                             after = along(keys[a + 1].s);
      hedgeRim_ = !(before && after && after->outerHorizon() > before->outerHorizon());
    }
    const double va = viewAngleOf(*keys[a].records, width, height);
    // Each key's samples made once, and only for the pairs that are matched here.
    std::map<std::size_t, FrameSamples> made;
    auto samples = [&](std::size_t k) -> const FrameSamples&
    {
      auto found = made.find(k);
      if (found == made.end())
        found = made
                  .emplace(k, samplesFromRecords(*keys[k].records, width, height, va,
                                                 "key " + std::to_string(k)))
                  .first;
      return found->second;
    };
    auto match = [&](std::size_t from, std::size_t to)
    {
      auto make = [&] { return matchFrames(samples(from), samples(to), index); };
      return cache ? cache->matches(keyFingerprint(keys[from]), keyFingerprint(keys[to]), make)
                   : std::make_shared<const Correspondence>(make());
    };
    const std::shared_ptr<const Correspondence> inner = match(a, a + 1);
    std::shared_ptr<const Correspondence> left, right;
    const bool hasLeft = a > 0, hasRight = a + 2 < keys.size();
    if (hasLeft)
      left = match(a - 1, a);
    if (hasRight)
      right = match(a + 1, a + 2);
    // Per inner key: its map to the other inner key, and to its own outer neighbour.
    const std::vector<PixelMatch>* toOther[2] = { &inner->aToB, &inner->bToA };
    const std::vector<PixelMatch>* toOuter[2] = { hasLeft ? &left->bToA : nullptr,
                                                  hasRight ? &right->aToB : nullptr };
    const double sInner[2] = { keys[a].s, keys[a + 1].s };
    const double sOuter[2] = { hasLeft ? keys[a - 1].s : 0.0, hasRight ? keys[a + 2].s : 0.0 };
    const std::size_t n = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
    movers_.resize(2 * n);
#pragma omp parallel for schedule(static)
    for (std::int64_t k = 0; k < static_cast<std::int64_t>(2 * n); ++k)
    {
      const int side = k < static_cast<std::int64_t>(n) ? 0 : 1;
      const std::size_t p = static_cast<std::size_t>(k) - side * n;
      const RayRecord& r = (*keys[a + side].records)[p];
      Mover& m = movers_[static_cast<std::size_t>(k)];
      m.record = &r;
      m.side = static_cast<std::uint8_t>(side);
      m.length = r.termination == Termination::Captured ? std::numeric_limits<double>::infinity()
                                                        : r.affineLength;
      if (!followable(r))
        continue;
      const int other = 1 - side;
      const PixelMatch& toB = (*toOther[side])[p];
      double s[4], x[4], y[4];
      int count = 0;
      auto node = [&](double sk, double xk, double yk)
      {
        s[count] = sk;
        x[count] = xk;
        y[count++] = yk;
      };
      node(sInner[side], static_cast<double>(p % width), static_cast<double>(p / width));
      node(sInner[other], toB.x, toB.y);
      double w[4];
      lagrangeWeights(s, 2, t, w);
      m.lin[0] = w[0] * x[0] + w[1] * x[1];
      m.lin[1] = w[0] * y[0] + w[1] * y[1];
      if (toOuter[side] && (*toOuter[side])[p].kind == MatchKind::Matched)
        node(sOuter[side], (*toOuter[side])[p].x, (*toOuter[side])[p].y);
      if (toB.kind == MatchKind::Matched && toOuter[other] && toB.partner >= 0)
      {
        const std::size_t q = static_cast<std::size_t>(toB.partner);
        const PixelMatch& beyond = (*toOuter[other])[q];
        if (beyond.kind == MatchKind::Matched)
        {
          // The point lies off the partner's centre: carry the offset through its map.
          const double ox = toB.x - static_cast<double>(q % width);
          const double oy = toB.y - static_cast<double>(q / width);
          const auto& J = beyond.jacobian;
          node(sOuter[other], beyond.x + J[0] * ox + J[1] * oy, beyond.y + J[2] * ox + J[3] * oy);
        }
      }
      lagrangeWeights(s, count, t, w);
      for (int c = 0; c < count; ++c)
      {
        m.x[0] += w[c] * x[c];
        m.x[1] += w[c] * y[c];
      }
      // The pixel's unit square maps to t by (1 − τ)·I + τ·D.
      const double tau = (t - sInner[side]) / (sInner[other] - sInner[side]);
      const auto& D = toB.jacobian;
      const double M[4] = { 1 - tau + tau * D[0], tau * D[1], tau * D[2], 1 - tau + tau * D[3] };
      const double det = M[0] * M[3] - M[1] * M[2];
      const double hx = 0.5 * (std::abs(M[0]) + std::abs(M[1]));
      const double hy = 0.5 * (std::abs(M[2]) + std::abs(M[3]));
      if (!(std::abs(det) > 1e-3) || !(hx + kGap < kReach) || !(hy + kGap < kReach) ||
          !std::isfinite(m.x[0] + m.x[1] + m.lin[0] + m.lin[1]))
        continue;
      m.inv[0] = M[3] / det;
      m.inv[1] = -M[1] / det;
      m.inv[2] = -M[2] / det;
      m.inv[3] = M[0] / det;
      // It covers spots (or lies within kGap of them) only where its offset d, x − c = M·d, has
      // |d|∞ ≤ ½ + kGap: within (1 + 2 kGap)·h of its centre along each axis, so within the
      // ceiling of that many cells of the spot's (at most kReach: no further is searched).
      m.reach = static_cast<std::uint8_t>(std::min(
        kReach, static_cast<int>(std::ceil((1.0 + 2.0 * kGap) * std::max(hx, hy) + 1e-6))));
      m.usable = true;
      if (atT_ && horizonAtT_ > 0.0 && r.termination == Termination::HitObject)
      {
        Vec4 x;
        x << 0.0, r.hitPoint;
        m.swallowed = atT_->radius(x) <= horizonAtT_;
      }
    }
    bucket(false, full_);
    bucket(true, linear_);
  }

  /// One key's scene points where the key itself shows them (at its own parameter): each covers
  /// its own pixel's unit square, as key a's points do at t = s_a. Nothing is matched.
  EdgeMover(const std::vector<RayRecord>& key, int width, int height)
    : width_(width)
    , height_(height)
    , atT_(nullptr)
    , horizonAtT_(0.0)
  {
    const std::size_t n = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
    movers_.resize(n);
    for (std::size_t p = 0; p < n; ++p)
    {
      Mover& m = movers_[p];
      m.record = &key[p];
      m.length = key[p].termination == Termination::Captured
                   ? std::numeric_limits<double>::infinity()
                   : key[p].affineLength;
      if (!followable(key[p]))
        continue;
      m.x[0] = m.lin[0] = static_cast<double>(p % static_cast<std::size_t>(width));
      m.x[1] = m.lin[1] = static_cast<double>(p / static_cast<std::size_t>(width));
      m.reach = 1; // (1 + 2 kGap) · ½ rounded up
      m.usable = true;
    }
    // Only the positions through every key are asked for (at a key the inner pair's line is the
    // same place): the linear grid stays empty, and a spot searched in it finds no mover.
    bucket(false, full_);
  }

  /// The front mover covering spot (x, y) at t, −1 if none: with the positions through every
  /// matched key or through the inner pair alone, the movers of the sides in `sides` (bit 0: key
  /// a's, bit 1: key a + 1's).
  std::int64_t front(double x, double y, bool linear, int sides) const
  {
    std::int64_t best = -1, nearest = -1;
    double bestLength = 0, nearestGap = kGap;
    this->visitNear(
      x, y, linear, sides,
      [&](std::int64_t k, const Mover& m, const double* d)
      {
        if (!onSurface(m, d))
          return false;
        const double out = std::max(std::abs(d[0]), std::abs(d[1])) - 0.5;
        if (out <= kSeam)
        {
          if (best < 0 || m.length < bestLength || (m.length == bestLength && k < best))
          {
            best = k;
            bestLength = m.length;
          }
        }
        else if (out < nearestGap || (out == nearestGap && nearest >= 0 && k < nearest))
        {
          nearest = k;
          nearestGap = out;
        }
        return false;
      });
    return best >= 0 ? best : nearest;
  }

  /// A mover of a ray the hole captured that covers spot (x, y) at t, −1 if none.
  std::int64_t capturedCovering(double x, double y, bool linear, int sides) const
  {
    std::int64_t found = -1;
    this->visitNear(x, y, linear, sides,
                    [&](std::int64_t k, const Mover& m, const double* d)
                    {
                      if (m.record->termination != Termination::Captured ||
                          std::max(std::abs(d[0]), std::abs(d[1])) - 0.5 > kSeam)
                        return false;
                      found = k;
                      return true;
                    });
    return found;
  }

  /// Mover k's record as the frame at t shows it: a scene point inside the hole's outer horizon
  /// at t (Mover::swallowed) gives way to the hole.
  RayRecord shown(std::int64_t k) const
  {
    const Mover& m = this->mover(k);
    RayRecord r = *m.record;
    if (m.swallowed)
    {
      r.termination = Termination::Captured;
      r.objectId = -1;
      r.imageOrder = 0;
    }
    return r;
  }

  /// Whether the shadow's rim may be hedged here (PathEdges.h, The shadow's rim).
  bool hedgeRim() const
  {
    return hedgeRim_;
  }

  const Mover& mover(std::int64_t k) const
  {
    return movers_[static_cast<std::size_t>(k)];
  }

  /// Spot (x, y) in the mover's source pixel's coordinates, relative to its centre.
  void offset(const Mover& m, double x, double y, bool linear, double* d) const
  {
    const double* c = linear ? m.lin : m.x;
    const double ex = x - c[0], ey = y - c[1];
    d[0] = m.inv[0] * ex + m.inv[1] * ey;
    d[1] = m.inv[2] * ex + m.inv[3] * ey;
  }

private:
  /// Calls visit(k, mover, d) for each usable mover of the sides in `sides` bucketed within
  /// kReach of spot (x, y) (through every matched key or, `linear`, the inner pair alone), d the
  /// spot in its source pixel's coordinates; stops once visit returns true.
  template<typename Visit>
  void visitNear(double x, double y, bool linear, int sides, Visit&& visit) const
  {
    const Grid& g = linear ? linear_ : full_;
    const int ci = static_cast<int>(std::floor(x + 0.5)),
              cj = static_cast<int>(std::floor(y + 0.5));
    for (int dj = -kReach; dj <= kReach; ++dj)
      for (int di = -kReach; di <= kReach; ++di)
      {
        const int cell = g.cell(ci + di, cj + dj);
        // Cells whose movers all reach less far cannot cover the spot: the same movers are found,
        // in the same order, as by searching every cell.
        if (cell < 0 ||
            g.reach[static_cast<std::size_t>(cell)] < std::max(std::abs(di), std::abs(dj)))
          continue;
        for (std::int64_t e = g.start[cell]; e < g.start[cell + 1]; ++e)
        {
          const std::int64_t k = g.entries[static_cast<std::size_t>(e)];
          const Mover& m = movers_[static_cast<std::size_t>(k)];
          if (!((sides >> m.side) & 1))
            continue;
          double d[2];
          this->offset(m, x, y, linear, d);
          if (visit(k, m, d))
            return;
        }
      }
  }

  /// The usable movers by the pixel their position at t rounds to, in a grid widened by kReach.
  struct Grid
  {
    int w = 0, h = 0;
    std::vector<std::int64_t> start, entries;
    std::vector<std::uint8_t> reach; ///< per cell, the farthest its movers reach (Mover::reach)
    int cell(int i, int j) const
    {
      i += kReach;
      j += kReach;
      return i >= 0 && i < w && j >= 0 && j < h ? j * w + i : -1;
    }
  };

  void bucket(bool linear, Grid& g)
  {
    g.w = width_ + 2 * kReach;
    g.h = height_ + 2 * kReach;
    std::vector<int> cellOf(movers_.size(), -1);
    g.start.assign(static_cast<std::size_t>(g.w) * g.h + 1, 0);
    g.reach.assign(static_cast<std::size_t>(g.w) * g.h, 0);
    for (std::size_t k = 0; k < movers_.size(); ++k)
    {
      if (!movers_[k].usable)
        continue;
      const double* c = linear ? movers_[k].lin : movers_[k].x;
      if (!(std::abs(c[0]) < 1e6 && std::abs(c[1]) < 1e6))
        continue;
      cellOf[k] =
        g.cell(static_cast<int>(std::floor(c[0] + 0.5)), static_cast<int>(std::floor(c[1] + 0.5)));
      if (cellOf[k] >= 0)
      {
        ++g.start[static_cast<std::size_t>(cellOf[k]) + 1];
        std::uint8_t& r = g.reach[static_cast<std::size_t>(cellOf[k])];
        r = std::max(r, movers_[k].reach);
      }
    }
    std::partial_sum(g.start.begin(), g.start.end(), g.start.begin());
    g.entries.resize(static_cast<std::size_t>(g.start.back()));
    std::vector<std::int64_t> fill(g.start.begin(), g.start.end() - 1);
    for (std::size_t k = 0; k < movers_.size(); ++k)
      if (cellOf[k] >= 0)
        g.entries[static_cast<std::size_t>(fill[static_cast<std::size_t>(cellOf[k])]++)] =
          static_cast<std::int64_t>(k);
  }

  int width_, height_;
  std::shared_ptr<const Spacetime> atT_;
  double horizonAtT_;
  bool hedgeRim_ = true;
  std::vector<Mover> movers_;
  Grid full_, linear_;
};

/// The record a mover shows at spot (x, y): its scene point's surface coordinates moved by the
/// spot's offset within its source pixel, and the footprint of a pixel at t scaled by `scale`.
RayRecord movedRecord(const EdgeMover& mover, std::int64_t k, double x, double y, bool linear,
                      double scale)
{
  const Mover& m = mover.mover(k);
  RayRecord r = mover.shown(k);
  if (r.objectId < 0)
    return r;
  double d[2];
  mover.offset(m, x, y, linear, d);
  const double J[4] = { r.dudi, r.dudj, r.dvdi, r.dvdj };
  const bool footprint = std::isfinite(J[0] + J[1] + J[2] + J[3]);
  if (footprint)
  {
    const double u = r.u + J[0] * d[0] + J[1] * d[1];
    r.u = u - std::floor(u);
    r.v = std::clamp(r.v + J[2] * d[0] + J[3] * d[1], 0.0, 1.0);
    // ∂(u, v)/∂(spot) = J · M⁻¹.
    r.dudi = scale * (J[0] * m.inv[0] + J[1] * m.inv[2]);
    r.dudj = scale * (J[0] * m.inv[1] + J[1] * m.inv[3]);
    r.dvdi = scale * (J[2] * m.inv[0] + J[3] * m.inv[2]);
    r.dvdj = scale * (J[2] * m.inv[1] + J[3] * m.inv[3]);
  }
  return r;
}

/// Sub-positions of a pixel, as a 3×3 supersampled trace places its rays (the adaptive
/// anti-aliasing's pattern at its default 9 rays).
constexpr double kSub[9][2] = { { -1 / 3.0, -1 / 3.0 }, { 0, -1 / 3.0 }, { 1 / 3.0, -1 / 3.0 },
                                { -1 / 3.0, 0 },        { 0, 0 },        { 1 / 3.0, 0 },
                                { -1 / 3.0, 1 / 3.0 },  { 0, 1 / 3.0 },  { 1 / 3.0, 1 / 3.0 } };

/// The centres of a pixel's 8 neighbours, relative to its own.
constexpr double kNeighbours[8][2] = { { -1, 0 },  { 1, 0 },  { 0, -1 }, { 0, 1 },
                                       { -1, -1 }, { 1, -1 }, { -1, 1 }, { 1, 1 } };
/// The squared share of the contrast with a neighbour that an edge misplaced by about half a
/// pixel leaves in the pixel's colour.
constexpr float kEdgeShare = 0.25f;
/// The same where every way of moving shows the pixel's centre alike: the edge then lies within
/// about a quarter of a pixel of where they put it (PathEdges.h, Estimate).
constexpr float kAgreedEdgeShare = 0.0625f;

/// A front mover not searched for yet (front() returns −1 where none covers a spot).
constexpr std::int64_t kNotSearched = -2;

/// Whether the ways of moving dispute what the centre of pixel (i, j) shows (`centre`, the front
/// point through every matched key): the inner pair alone, or either inner key's points alone,
/// show another surface there or nothing, or, where it shows a surface, the hole's moved rays
/// cover it too (the shadow's rim).
/// `fronts` holds those ways' front movers at the centre where subsampled() found them already
/// (kNotSearched where it stopped before the centre).
bool disputed(const EdgeMover& mover, int i, int j, const RayRecord& centre,
              const std::int64_t (&fronts)[3])
{
  const bool linear[3] = { true, false, false };
  const int sides[3] = { 3, 1, 2 };
  for (int w = 0; w < 3; ++w)
  {
    const std::int64_t k =
      fronts[w] != kNotSearched ? fronts[w] : mover.front(i, j, linear[w], sides[w]);
    if (k < 0 || !endAlike(centre, mover.shown(k)))
      return true;
  }
  return centre.termination != Termination::Captured && mover.capturedCovering(i, j, false, 3) >= 0;
}

/// The mean colour of the pixel's sub-positions as one way of moving predicts it; false if a
/// sub-position is covered by nothing. `centre` (if given) and the sub-positions' records ending
/// alike leave `alike` (if given) true. `centreFront` (if given) gets the front mover at the
/// pixel's centre, if the search got that far.
bool subsampled(const EdgeMover& mover, const Scene& scene, int i, int j, bool linear, int sides,
                Color& out, const RayRecord* centre = nullptr, bool* alike = nullptr,
                float* nearShadow = nullptr, bool hedgeNearShadow = false,
                std::int64_t* centreFront = nullptr, const std::vector<Color>* residuals = nullptr,
                Color* residual = nullptr)
{
  out = Color::Zero();
  if (residual)
    *residual = Color::Zero();
  Color halfContrast = Color::Zero();
  for (const auto& o : kSub)
  {
    const double x = i + o[0], y = j + o[1];
    const std::int64_t k = mover.front(x, y, linear, sides);
    if (centreFront && o[0] == 0 && o[1] == 0)
      *centreFront = k;
    if (k < 0)
      return false;
    if (residuals && residual)
      *residual += (*residuals)[static_cast<std::size_t>(k)] / 9.0;
    const RayRecord r = movedRecord(mover, k, x, y, linear, 1 / 3.0);
    if (centre && alike && !endAlike(*centre, r))
      *alike = false;
    Color c = shadePrediction(scene, r);
    // The shadow's rim (PathEdges.h): the mean of the two, half the contrast off whichever shows.
    if (hedgeNearShadow && mover.hedgeRim() && r.termination != Termination::Captured)
    {
      const std::int64_t h = mover.capturedCovering(x, y, linear, sides);
      if (h >= 0)
      {
        const Color shadow = shadePrediction(scene, *mover.mover(h).record);
        halfContrast += 0.5 * (c - shadow) / 9.0;
        c = 0.5 * (c + shadow);
      }
    }
    out += c / 9.0;
  }
  if (nearShadow) // the error of the mean where the other is right
    *nearShadow = colorError2(halfContrast, Color::Zero());
  return true;
}

/// Each pixel of a key within a pixel of an edge in it (one of its 8 neighbours ends otherwise):
/// its traced colour less the mean of its 3×3 sub-positions as the key's own points show them
/// (PathEdges.h, The keys' own residual); 0 elsewhere. Appended to `out`, pixel order.
void appendOwnResiduals(const std::vector<RayRecord>& key, int width, int height,
                        const Scene& scene, std::vector<Color>& out)
{
  const std::size_t base = out.size();
  const std::size_t n = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
  out.resize(base + n, Color::Zero());
  const EdgeMover own(key, width, height);
#pragma omp parallel for schedule(dynamic, 256)
  for (std::int64_t q = 0; q < static_cast<std::int64_t>(n); ++q)
  {
    const int i = static_cast<int>(q % width), j = static_cast<int>(q / width);
    const RayRecord& r = key[static_cast<std::size_t>(q)];
    bool nearEdge = false;
    for (int dj = -1; dj <= 1 && !nearEdge; ++dj)
      for (int di = -1; di <= 1 && !nearEdge; ++di)
      {
        const int x = i + di, y = j + dj;
        if (x >= 0 && x < width && y >= 0 && y < height)
          nearEdge = !endAlike(r, key[static_cast<std::size_t>(y) * width + x]);
      }
    Color shown;
    if (nearEdge && subsampled(own, scene, i, j, false, 1, shown))
      out[base + static_cast<std::size_t>(q)] = r.color - shown;
  }
}

/// The squared colour difference (levels² of 255, summed over the channels) between `color` and
/// the nearer of the inner keys' (a, a + 1) colours at pixel p.
float awayFromInnerKeys(const std::vector<PathKey>& keys, std::size_t a, std::int32_t p,
                        const Color& color)
{
  const std::size_t k = static_cast<std::size_t>(p);
  return std::min(colorError2(color, (*keys[a].records)[k].color),
                  colorError2(color, (*keys[a + 1].records)[k].color));
}
}

std::vector<MovedEdgePixel> predictMovedEdges(
  const std::vector<PathKey>& keys, std::size_t a, double t, int width, int height,
  const Scene& scene, const PointIndexFactory& index, const std::vector<std::int32_t>& pixels,
  const std::vector<const RayRecord*>& perPixel, bool hedged, bool hedgeNearShadow,
  PathMatchCache* cache, const SpacetimeAlongPath& along, double residualShare)
{
  std::vector<MovedEdgePixel> out(pixels.size());
  if (pixels.empty())
    return out;
  const EdgeMover mover(keys, a, t, width, height, index, cache, along);
  // The inner keys' own residuals, by mover (key a's pixels, then key a + 1's).
  std::vector<Color> residuals;
  if (residualShare > 0.0)
    for (std::size_t side : { a, a + 1 })
      appendOwnResiduals(*keys[side].records, width, height, scene, residuals);
#pragma omp parallel for schedule(dynamic, 16)
  for (std::int64_t q = 0; q < static_cast<std::int64_t>(pixels.size()); ++q)
  {
    MovedEdgePixel& e = out[static_cast<std::size_t>(q)];
    const int i = pixels[static_cast<std::size_t>(q)] % width;
    const int j = pixels[static_cast<std::size_t>(q)] / width;
    Color color;
    const std::int64_t centre = mover.front(i, j, false, 3);
    if (centre < 0)
      continue;
    const RayRecord centreRecord = movedRecord(mover, centre, i, j, false, 1.0);
    bool oneSurface = true;
    float nearShadow = 0.0f;
    Color residual = Color::Zero();
    if (!subsampled(mover, scene, i, j, false, 3, color, &centreRecord, &oneSurface, &nearShadow,
                    hedgeNearShadow, nullptr, residuals.empty() ? nullptr : &residuals, &residual))
      continue;
    e.covered = true;
    e.record = centreRecord;
    e.record.i = i;
    e.record.j = j;
    e.record.raysPerPixel = static_cast<std::int32_t>(std::size(kSub));
    e.record.color = color;
    // The other ways of predicting the pixel: the disagreement of each with this one.
    Color other, sum = color;
    int ways = 1;
    std::int64_t fronts[3] = { kNotSearched, kNotSearched, kNotSearched };
    if (subsampled(mover, scene, i, j, true, 3, other, nullptr, nullptr, nullptr, hedgeNearShadow,
                   &fronts[0]))
      e.estimate = std::max(e.estimate, colorError2(color, other));
    else
      e.estimate = std::numeric_limits<float>::infinity();
    for (int side : { 1, 2 })
      if (subsampled(mover, scene, i, j, false, side, other, nullptr, nullptr, nullptr,
                     hedgeNearShadow, &fronts[side]))
      {
        e.estimate = std::max(e.estimate, colorError2(color, other));
        sum += other;
        ++ways;
      }
    const bool isDisputed = disputed(mover, i, j, centreRecord, fronts);
    if (hedged)
      e.record.color = sum / static_cast<double>(ways);
    // An edge within a pixel of it that every prediction moves alike may still lie a fraction of
    // a pixel off, which changes the pixel by that fraction of the contrast across the edge.
    const float share = isDisputed ? kEdgeShare : kAgreedEdgeShare;
    // The front movers at the neighbours' centres: whether an edge lies within a pixel.
    std::int64_t neighbour[std::size(kNeighbours)];
    for (std::size_t n = 0; n < std::size(kNeighbours); ++n)
    {
      const double x = i + kNeighbours[n][0], y = j + kNeighbours[n][1];
      neighbour[n] = mover.front(x, y, false, 3);
      oneSurface = oneSurface && neighbour[n] >= 0 &&
                   endAlike(centreRecord, movedRecord(mover, neighbour[n], x, y, false, 1.0));
    }
    // Across an edge, the contrast with the neighbours' centres. Off the edges the contrast is the
    // texture's, and a misplacement of up to half a pixel brings to the pixel only the texture
    // within half a pixel of it: the neighbours' centres would count colours a pixel away, which
    // leave a pixel of one colour as it is.
    const double reach = oneSurface ? 0.5 : 1.0;
    float contrast = 0.0f;
    for (std::size_t n = 0; n < std::size(kNeighbours); ++n)
    {
      const double x = i + reach * kNeighbours[n][0], y = j + reach * kNeighbours[n][1];
      const std::int64_t k = oneSurface ? mover.front(x, y, false, 3) : neighbour[n];
      if (k >= 0)
        contrast = std::max(
          contrast,
          colorError2(color, shadePrediction(scene, movedRecord(mover, k, x, y, false, 1.0))));
    }
    e.oneSurface = oneSurface;
    // Within one surface the contrast is the texture's, as the pixel moves by a fraction of itself.
    contrast *= oneSurface ? kEdgeShare : share;
    e.estimate = std::max({ e.estimate, contrast, nearShadow });
    // Where an edge crosses the pixel, the keys' own residual carried with the points that cover
    // it: where within their pixels the keys saw the edge (PathEdges.h, The keys' own residual).
    // It holds only in part at t, by about its own size: that adds to the estimate.
    if (!oneSurface)
    {
      e.record.color += residualShare * residual;
      e.estimate += colorError2(residual, Color::Zero());
    }
    if (const RayRecord* own = perPixel[static_cast<std::size_t>(q)])
    {
      e.estimate = std::max(e.estimate, colorError2(color, own->color));
      // Where the edge leaves the pixel's own ray on the object it ends on at both keys, the
      // per-pixel prediction, which follows the surface through every key, is kept.
      if (own->objectId == e.record.objectId && own->termination == e.record.termination)
        e.record = *own;
    }
    // Across an edge the pixel shows at t what one of the inner keys shows there, give or take
    // the texture's motion: a colour far from both is one the prediction made up (a blend, or a
    // third surface), an error of its own beside the edge's misplacement, which adds.
    if (!e.oneSurface)
      e.estimate += awayFromInnerKeys(keys, a, pixels[static_cast<std::size_t>(q)], e.record.color);
  }
  return out;
}
}
