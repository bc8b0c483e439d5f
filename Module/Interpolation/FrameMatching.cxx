#include "FrameMatching.h"

#include "FrameInterpolation.h"
#include "SceneFile.h"

#include <nlohmann/json.hpp>
#include <omp.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <map>
#include <sstream>

namespace asrt
{
PointIndex::~PointIndex() = default;

std::array<std::uint8_t, 3> imageColor(const Color& c)
{
  std::array<std::uint8_t, 3> out;
  for (int k = 0; k < 3; ++k)
    out[k] = static_cast<std::uint8_t>(std::lround(255.0 * std::clamp(c[k], 0.0, 1.0)));
  return out;
}

PixelSample sampleOf(const RayRecord& r)
{
  if (!r.color.allFinite())
    throw InvalidParameter("its colour is not finite");
  PixelSample s;
  s.point = r.hitPoint;
  s.u = r.u;
  s.v = r.v;
  s.jacobian = { { r.dudi, r.dudj, r.dvdi, r.dvdj } };
  s.pathLength = r.affineLength;
  s.objectId = r.objectId;
  s.imageOrder = r.imageOrder;
  s.termination = r.termination;
  s.rgb = imageColor(r.color);
  return s;
}

SampleKind kindOf(const PixelSample& s)
{
  if (s.termination == Termination::HitObject && s.objectId >= 0)
    return SampleKind::Surface;
  if (s.termination == Termination::Escaped && s.objectId < 0)
    return SampleKind::Escaped;
  if (s.termination == Termination::Captured)
    return SampleKind::Shadow;
  return SampleKind::Lost;
}

FrameSamples assembleFrame(int width, int height, double viewAngle, std::size_t count,
                           const std::function<void(std::size_t, int&, int&, PixelSample&)>& next,
                           const std::string& which)
{
  if (width <= 0 || height <= 0)
  {
    std::ostringstream os;
    os << which << ": resolution must be positive, got " << width << " x " << height;
    throw InvalidParameter(os.str());
  }
  if (!(viewAngle > 0 && viewAngle < 180))
    throw InvalidParameter(which + ": view angle must lie in (0, 180) degrees");
  const std::size_t n = static_cast<std::size_t>(width) * height;
  if (count != n)
  {
    std::ostringstream os;
    os << which << " holds " << count << " rays, but a whole " << width << " x " << height
       << " frame has " << n << " (frames of only some pixels cannot be interpolated)";
    throw InvalidParameter(os.str());
  }
  FrameSamples f;
  f.width = width;
  f.height = height;
  f.viewAngle = viewAngle;
  f.pixels.resize(n);
  std::vector<std::uint8_t> seen(n, 0);
  for (std::size_t k = 0; k < count; ++k)
  {
    PixelSample s;
    int i = -1, j = -1;
    auto refuse = [&](const std::string& why)
    {
      std::ostringstream os;
      os << which << ", ray " << k;
      if (i >= 0 && j >= 0)
        os << " (pixel " << i << ", " << j << ")";
      os << ": " << why;
      throw InvalidParameter(os.str());
    };
    try
    {
      next(k, i, j, s);
    }
    catch (const InvalidParameter& e)
    {
      refuse(e.what());
    }
    if (i < 0 || i >= width || j < 0 || j >= height)
      refuse("its pixel lies outside the frame");
    const std::size_t p = static_cast<std::size_t>(j) * width + i;
    if (seen[p])
      refuse("a second ray for this pixel");
    seen[p] = 1;
    if (!std::isfinite(s.pathLength))
      refuse("its path length is not finite");
    const SampleKind kind = kindOf(s);
    if ((kind == SampleKind::Surface || kind == SampleKind::Escaped) && !s.point.allFinite())
      refuse("its hit point is not finite");
    if (kind == SampleKind::Surface && !(std::isfinite(s.u) && std::isfinite(s.v)))
      refuse("its surface coordinates are not finite");
    f.pixels[p] = s;
  }
  return f;
}

FrameSamples samplesFromRecords(const std::vector<RayRecord>& records, int width, int height,
                                double viewAngle, const std::string& which)
{
  return assembleFrame(
    width, height, viewAngle, records.size(),
    [&](std::size_t k, int& i, int& j, PixelSample& s)
    {
      i = records[k].i;
      j = records[k].j;
      s = sampleOf(records[k]);
    },
    which);
}

namespace
{
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

using Mat2 = Eigen::Matrix2d;
using Vec2 = Eigen::Vector2d;

/// u is periodic on closed surfaces: differences are taken the short way round.
double wrapped(double du)
{
  return du - std::round(du);
}

/// A frame prepared for matching: what each ray ended on and how large a pixel is there.
struct FrameView
{
  const FrameSamples& f;
  std::vector<SampleKind> kind;
  std::vector<double> footprint; ///< world distance to the nearest neighbour of the same image

  explicit FrameView(const FrameSamples& frame)
    : f(frame)
  {
    const std::size_t n = frame.pixels.size();
    kind.resize(n);
    for (std::size_t p = 0; p < n; ++p)
      kind[p] = kindOf(frame.pixels[p]);
    footprint.assign(n, kNaN);
    const double pixelAngle =
      2.0 * std::tan(0.5 * frame.viewAngle * M_PI / 180.0) / static_cast<double>(frame.height);
    const int W = frame.width, H = frame.height;
#pragma omp parallel for schedule(static)
    for (int j = 0; j < H; ++j)
      for (int i = 0; i < W; ++i)
      {
        const std::size_t p = static_cast<std::size_t>(j) * W + i;
        if (!this->pointLike(p))
          continue;
        auto gap = [&](int ii, int jj)
        {
          if (ii < 0 || ii >= W || jj < 0 || jj >= H)
            return std::numeric_limits<double>::infinity();
          const std::size_t q = static_cast<std::size_t>(jj) * W + ii;
          return this->sameImage(p, q) ? (frame.pixels[q].point - frame.pixels[p].point).norm()
                                       : std::numeric_limits<double>::infinity();
        };
        // The nearer neighbour on each axis: a jump to another part of the object on one side
        // does not inflate the footprint.
        const double di = std::min(gap(i - 1, j), gap(i + 1, j));
        const double dj = std::min(gap(i, j - 1), gap(i, j + 1));
        double fp = 0;
        if (std::isfinite(di))
          fp = di;
        if (std::isfinite(dj))
          fp = std::max(fp, dj);
        if (!std::isfinite(di) && !std::isfinite(dj))
          // An isolated pixel: a ray bundle one pixel wide at its path length, twice over.
          fp = 2.0 * frame.pixels[p].pathLength * pixelAngle;
        footprint[p] = std::max(fp, 1e-12 * (1.0 + frame.pixels[p].point.norm()));
      }
  }

  bool pointLike(std::size_t p) const
  {
    return kind[p] == SampleKind::Surface || kind[p] == SampleKind::Escaped;
  }
  bool sameImage(std::size_t p, std::size_t q) const
  {
    const PixelSample &a = f.pixels[p], &b = f.pixels[q];
    return kind[p] == kind[q] && pointLike(q) && a.objectId == b.objectId &&
           a.imageOrder == b.imageOrder;
  }
  /// The hit's tangent along i (axis 0) or j (axis 1) from neighbours of the same image.
  bool tangent(std::size_t p, int axis, Vec3& t) const
  {
    const int W = f.width, H = f.height;
    const int i = static_cast<int>(p % W), j = static_cast<int>(p / W);
    auto at = [&](int s) -> const PixelSample*
    {
      const int ii = axis == 0 ? i + s : i, jj = axis == 1 ? j + s : j;
      if (ii < 0 || ii >= W || jj < 0 || jj >= H)
        return nullptr;
      const std::size_t q = static_cast<std::size_t>(jj) * W + ii;
      return this->sameImage(p, q) ? &f.pixels[q] : nullptr;
    };
    const PixelSample *minus = at(-1), *plus = at(1);
    if (minus && plus)
      t = 0.5 * (plus->point - minus->point);
    else if (plus)
      t = plus->point - f.pixels[p].point;
    else if (minus)
      t = f.pixels[p].point - minus->point;
    else
      return false;
    return true;
  }
  bool tangents(std::size_t p, Eigen::Matrix<double, 3, 2>& T) const
  {
    Vec3 ti, tj;
    if (!this->tangent(p, 0, ti) || !this->tangent(p, 1, tj))
      return false;
    T.col(0) = ti;
    T.col(1) = tj;
    return true;
  }
  /// Where the point of sample s lies relative to pixel q of this frame, in pixels, by q's local
  /// linear map: Δ(i, j) = J⁻¹ Δ(u, v) (u the short way round), or from q's neighbours' hits
  /// where (u, v) has no Jacobian or gives a far point. NaN if neither is known.
  Vec2 offset(std::size_t q, const PixelSample& s) const
  {
    const PixelSample& t = f.pixels[q];
    Vec2 delta(kNaN, kNaN);
    Mat2 J;
    if (this->uvJacobian(q, J))
      delta = J.inverse() * Vec2(wrapped(s.u - t.u), s.v - t.v);
    Eigen::Matrix<double, 3, 2> T;
    if ((!delta.allFinite() || delta.cwiseAbs().maxCoeff() > 2.0) && this->tangents(q, T))
    {
      const Mat2 G = T.transpose() * T;
      if (std::abs(G.determinant()) > 1e-12 * G.squaredNorm())
        delta = G.inverse() * (T.transpose() * (s.point - t.point));
    }
    return delta;
  }
  /// ∂(u, v)/∂(i, j) of the record, if it has one and it can be inverted.
  bool uvJacobian(std::size_t p, Mat2& J) const
  {
    const PixelSample& s = f.pixels[p];
    if (kind[p] != SampleKind::Surface)
      return false;
    J << s.jacobian[0], s.jacobian[1], s.jacobian[2], s.jacobian[3];
    if (!J.allFinite())
      return false;
    const double scale = J.squaredNorm();
    return scale > 0 && std::abs(J.determinant()) > 1e-9 * scale;
  }
};

struct Group
{
  std::vector<std::int32_t> pixels; ///< pixel of each indexed point
  std::vector<Vec3> points;
  std::unique_ptr<PointIndex> index;
  double maxFootprint = 0;
};
using GroupKey = std::pair<int, int>; ///< (object id, −1 for the empty sky; image order)

GroupKey groupOf(const PixelSample& s)
{
  return { s.objectId, s.imageOrder };
}

struct ShadowShape
{
  double count = 0;
  Vec2 centroid = Vec2::Zero();
  double radius = 0;
};

ShadowShape shadowOf(const FrameView& v)
{
  ShadowShape s;
  const int W = v.f.width;
  for (std::size_t p = 0; p < v.kind.size(); ++p)
    if (v.kind[p] == SampleKind::Shadow)
    {
      s.count += 1;
      s.centroid += Vec2(static_cast<double>(p % W), static_cast<double>(p / W));
    }
  if (s.count > 0)
  {
    s.centroid /= s.count;
    s.radius = std::sqrt(s.count / M_PI);
  }
  return s;
}

void setJacobian(PixelMatch& m, const Mat2& D)
{
  // Beyond 64× the map is meaningless for splatting (the renderer clamps far below that).
  for (int k = 0; k < 4; ++k)
    m.jacobian[k] = static_cast<float>(std::clamp(D(k / 2, k % 2), -64.0, 64.0));
}

/// The other frame's rays, one searchable set per (object, image order), and the set each pixel
/// of the frame matched from is looked for in.
struct TargetGroups
{
  std::map<GroupKey, Group> groups;
  std::vector<const Group*> ofPixel; ///< null: a lost ray, or its image is not in the other frame

  TargetGroups(const FrameView& from, const FrameView& to, const PointIndexFactory& makeIndex)
  {
    const std::size_t n = from.f.pixels.size();
    for (std::size_t q = 0; q < n; ++q)
      if (to.pointLike(q))
      {
        Group& g = this->groups[groupOf(to.f.pixels[q])];
        g.pixels.push_back(static_cast<std::int32_t>(q));
        g.points.push_back(to.f.pixels[q].point);
        g.maxFootprint = std::max(g.maxFootprint, to.footprint[q]);
      }
    // Built here, outside any OpenMP region: VTK builds its locators with vtkSMPTools (TBB).
    for (auto& [key, g] : this->groups)
      g.index = makeIndex(g.points);
    this->ofPixel.assign(n, nullptr);
    for (std::size_t p = 0; p < n; ++p)
      if (from.pointLike(p))
      {
        const auto it = this->groups.find(groupOf(from.f.pixels[p]));
        if (it != this->groups.end())
          this->ofPixel[p] = &it->second;
      }
  }
  TargetGroups(const TargetGroups&) = delete;
  TargetGroups& operator=(const TargetGroups&) = delete;
};

/// One thread's scratch for matching the pixels of a frame of n pixels. The patch of rays near a
/// point lives in dense arrays, stamped with the index of the pixel being matched, so that
/// membership costs O(1) (patches are large where an image is squeezed).
struct MatchScratch
{
  std::vector<std::int64_t> near;
  std::vector<std::int32_t> patch, stack, images;
  std::vector<std::int32_t> stamp, label;
  std::vector<std::pair<double, std::int32_t>> nearest, byLength;

  explicit MatchScratch(std::size_t n)
    : stamp(n, -1)
    , label(n, 0)
  {
  }
};

/// The shadow maps onto the other frame's shadow by their centroids and radii.
void matchShadowPixel(const FrameView& to, const ShadowShape& shadowFrom,
                      const ShadowShape& shadowTo, int i, int j, PixelMatch& m)
{
  const int W = to.f.width, H = to.f.height;
  const double scale = shadowTo.radius / shadowFrom.radius;
  const Vec2 x = shadowTo.centroid + scale * (Vec2(i, j) - shadowFrom.centroid);
  m.x = static_cast<float>(x.x());
  m.y = static_cast<float>(x.y());
  setJacobian(m, scale * Mat2::Identity());
  m.kind = MatchKind::Matched;
  const long qi = std::lround(x.x()), qj = std::lround(x.y());
  if (qi >= 0 && qi < W && qj >= 0 && qj < H &&
      to.kind[static_cast<std::size_t>(qj) * W + qi] == SampleKind::Shadow)
    m.partner = static_cast<std::int32_t>(qj * W + qi);
}

/// Labels the rays of sc.patch (stamped `query`) by 8-connected component in the pixel grid,
/// q0's component first (label 1). Returns the number of components.
std::int32_t labelPatches(const FrameView& to, std::int32_t q0, std::int32_t query,
                          MatchScratch& sc)
{
  const int W = to.f.width, H = to.f.height;
  std::int32_t patches = 0;
  const auto labelPatch = [&](std::int32_t seed)
  {
    sc.label[static_cast<std::size_t>(seed)] = ++patches;
    sc.stack.assign(1, seed);
    while (!sc.stack.empty())
    {
      const std::int32_t c = sc.stack.back();
      sc.stack.pop_back();
      const int ci = c % W, cj = c / W;
      for (int dj = -1; dj <= 1; ++dj)
        for (int di = -1; di <= 1; ++di)
        {
          const int ni = ci + di, nj = cj + dj;
          if ((di == 0 && dj == 0) || ni < 0 || ni >= W || nj < 0 || nj >= H)
            continue;
          const std::size_t nb = static_cast<std::size_t>(nj) * W + ni;
          if (sc.stamp[nb] != query || sc.label[nb])
            continue;
          sc.label[nb] = patches;
          sc.stack.push_back(static_cast<std::int32_t>(nb));
        }
    }
  };
  labelPatch(q0);
  for (const std::int32_t c : sc.patch)
    if (!sc.label[static_cast<std::size_t>(c)])
      labelPatch(c);
  return patches;
}

/// The images of the same order that show the point of sample s (pixel p), into sc.images: q0's
/// (the nearest ray's) first. The rays whose hits lie near the point form, in the pixel grid, one
/// connected patch per image (a small ball's preimage under a locally smooth map): patches not
/// connected to q0's are other images, if one of their hits is within tolerance of the point.
void imagesOfPoint(const FrameView& to, const Group& g, std::size_t p, const PixelSample& s,
                   std::int32_t q0, double tol, MatchScratch& sc)
{
  g.index->within(s.point, tol * to.footprint[q0], sc.near);
  const std::int32_t query = static_cast<std::int32_t>(p);
  sc.patch.clear();
  for (const std::int64_t k : sc.near)
  {
    const std::int32_t c = g.pixels[static_cast<std::size_t>(k)];
    sc.patch.push_back(c);
    sc.stamp[static_cast<std::size_t>(c)] = query;
    sc.label[static_cast<std::size_t>(c)] = 0;
  }
  const std::int32_t patches = labelPatches(to, q0, query, sc);
  sc.images.assign(1, q0);
  if (patches <= 1)
    return;
  // Each other patch is another image if the point lies on it: within a pixel of its nearest hit
  // by that pixel's local map (a distance alone is too loose where an image is squeezed along
  // one axis).
  sc.nearest.assign(static_cast<std::size_t>(patches) + 1,
                    { std::numeric_limits<double>::infinity(), -1 });
  for (const std::int32_t c : sc.patch)
  {
    const std::int32_t l = sc.label[static_cast<std::size_t>(c)];
    if (l == 1)
      continue;
    const double d = (s.point - to.f.pixels[c].point).norm();
    auto& best = sc.nearest[static_cast<std::size_t>(l)];
    if (d <= tol * to.footprint[c] && d < best.first)
      best = { d, c };
  }
  for (std::int32_t l = 2; l <= patches; ++l)
  {
    const std::int32_t c = sc.nearest[static_cast<std::size_t>(l)].second;
    if (c < 0)
      continue;
    const Vec2 delta = to.offset(static_cast<std::size_t>(c), s);
    if (!delta.allFinite() || delta.cwiseAbs().maxCoeff() <= 1.0)
      sc.images.push_back(c);
  }
}

/// Of nested images of one order (sc.images, more than one), the one whose path length is
/// closest to s's is the same image (the paper's rule), into q; false when two are equally
/// close and cannot be told apart.
bool closestByPathLength(const FrameView& to, const PixelSample& s, const MatchOptions& opt,
                         MatchScratch& sc, std::int32_t& q)
{
  sc.byLength.clear();
  for (const std::int32_t c : sc.images)
    sc.byLength.emplace_back(std::abs(to.f.pixels[c].pathLength - s.pathLength), c);
  std::sort(sc.byLength.begin(), sc.byLength.end());
  if (sc.byLength[1].first - sc.byLength[0].first <=
      opt.pathLengthTie * std::max(1.0, s.pathLength))
    return false;
  q = sc.byLength[0].second;
  return true;
}

/// Sub-pixel position of the point of s near pixel q of the other frame: q may move to a nearer
/// pixel of the same image, delta is the point's offset from it (within its cell). False when
/// the point is not seen there: the local map puts it beyond the frame's edge (it has left the
/// view), or more than a pixel beyond the image's last ray (the nearest ray was merely close).
bool refinePosition(const FrameView& to, const PixelSample& s, std::int32_t& q, Vec2& delta)
{
  const int W = to.f.width, H = to.f.height;
  // The nearest hit in space need not be the nearest pixel where an image is squeezed: step to
  // the pixel the local map points at (up to 3 px at a time) while that brings the point closer,
  // within the same image.
  delta = to.offset(static_cast<std::size_t>(q), s);
  bool leavesView = false;
  for (int step = 0; step < 8 && delta.allFinite() && delta.cwiseAbs().maxCoeff() > 0.5; ++step)
  {
    const int ni = q % W + static_cast<int>(std::clamp(std::lround(delta.x()), -3L, 3L));
    const int nj = q / W + static_cast<int>(std::clamp(std::lround(delta.y()), -3L, 3L));
    if (ni < 0 || ni >= W || nj < 0 || nj >= H)
    {
      leavesView = true;
      break;
    }
    const std::size_t next = static_cast<std::size_t>(nj) * W + ni;
    if (!to.sameImage(static_cast<std::size_t>(q), next))
      break;
    const Vec2 d = to.offset(next, s);
    if (!d.allFinite() || d.cwiseAbs().maxCoeff() >= delta.cwiseAbs().maxCoeff())
      break;
    q = static_cast<std::int32_t>(next);
    delta = d;
  }
  if (!delta.allFinite())
    delta.setZero();
  if (delta.cwiseAbs().maxCoeff() > 1.0 || (leavesView && delta.cwiseAbs().maxCoeff() > 0.5))
    return false;
  // Otherwise the point stays within the pixel's cell.
  delta = delta.cwiseMax(-0.5).cwiseMin(0.5);
  return true;
}

/// Pixel p matched at `delta` from pixel q of the other frame, its Jacobian from both frames'
/// (u, v) maps, else from their tangents; NaN (filled from the neighbours later) if neither.
void setMatched(const FrameView& from, const FrameView& to, std::size_t p, std::int32_t q,
                const Vec2& delta, PixelMatch& m)
{
  const int W = to.f.width;
  Mat2 Jq = Mat2::Zero(), Jp = Mat2::Zero();
  Eigen::Matrix<double, 3, 2> Tq = Eigen::Matrix<double, 3, 2>::Zero(), Tp = Tq;
  const bool uvq = to.uvJacobian(static_cast<std::size_t>(q), Jq);
  const bool tq = to.tangents(static_cast<std::size_t>(q), Tq);
  m.x = static_cast<float>(static_cast<double>(q % W) + delta.x());
  m.y = static_cast<float>(static_cast<double>(q / W) + delta.y());
  m.partner = q;
  m.kind = MatchKind::Matched;
  if (uvq && from.uvJacobian(p, Jp))
    setJacobian(m, Jq.inverse() * Jp);
  else if (tq && from.tangents(p, Tp))
  {
    const Mat2 G = Tq.transpose() * Tq;
    if (std::abs(G.determinant()) > 1e-12 * G.squaredNorm())
      setJacobian(m, G.inverse() * (Tq.transpose() * Tp));
    else
      m.jacobian[0] = std::numeric_limits<float>::quiet_NaN();
  }
  else
    m.jacobian[0] = std::numeric_limits<float>::quiet_NaN(); // from the neighbours, later
}

/// Matches pixel p, whose ray hit a point of group g's image, into the other frame; left
/// one-sided when the point is not seen there.
void matchPointPixel(const FrameView& from, const FrameView& to, const Group& g, std::size_t p,
                     const MatchOptions& opt, MatchScratch& sc, PixelMatch& m)
{
  const double tol = opt.tolerance;
  const PixelSample& s = from.f.pixels[p];
  const std::int64_t k0 = g.index->nearestWithin(s.point, tol * g.maxFootprint);
  if (k0 < 0)
    return;
  const std::int32_t q0 = g.pixels[static_cast<std::size_t>(k0)];
  const double d0 = (s.point - to.f.pixels[q0].point).norm();
  if (d0 > tol * to.footprint[q0])
    return; // the nearest ray of this image is too far: the point is not seen there
  imagesOfPoint(to, g, p, s, q0, tol, sc);
  std::int32_t q = q0;
  if (sc.images.size() > 1 && !closestByPathLength(to, s, opt, sc, q))
  {
    m.kind = MatchKind::Ambiguous;
    return;
  }
  Vec2 delta;
  if (refinePosition(to, s, q, delta))
    setMatched(from, to, p, q, delta, m);
}

/// Matches every pixel of `from` on its own (the OpenMP threads share them), reporting progress
/// from progress0 over progressSpan.
void matchPixels(const FrameView& from, const FrameView& to, const TargetGroups& targets,
                 const MatchOptions& opt, const std::function<void(double)>& progress,
                 double progress0, double progressSpan, std::vector<PixelMatch>& out)
{
  const int W = from.f.width;
  const std::size_t n = from.f.pixels.size();
  const ShadowShape shadowFrom = shadowOf(from), shadowTo = shadowOf(to);
  const bool shadowsMatch = shadowFrom.count > 0 && shadowTo.count > 0;
  std::atomic<std::size_t> done{ 0 };
#pragma omp parallel
  {
    MatchScratch scratch(n);
#pragma omp for schedule(dynamic, 512)
    for (std::int64_t pp = 0; pp < static_cast<std::int64_t>(n); ++pp)
    {
      const std::size_t p = static_cast<std::size_t>(pp);
      PixelMatch& m = out[p];
      const int i = static_cast<int>(p % W), j = static_cast<int>(p / W);
      m.x = static_cast<float>(i);
      m.y = static_cast<float>(j);
      if (progress && omp_get_thread_num() == 0 && (p & 0x3fff) == 0)
        progress(progress0 + progressSpan * static_cast<double>(done.load()) / n);
      if ((pp & 0xff) == 0xff)
        done += 256;
      if (from.kind[p] == SampleKind::Shadow)
      {
        if (shadowsMatch)
          matchShadowPixel(to, shadowFrom, shadowTo, i, j, m);
        continue;
      }
      if (const Group* g = targets.ofPixel[p])
        matchPointPixel(from, to, *g, p, opt, scratch, m);
    }
  }
}

/// Whether pixels p and q of a frame show the same image, the shadow counting as one.
bool sameImageOrShadow(const FrameView& v, std::size_t p, std::size_t q)
{
  if (v.kind[p] == SampleKind::Shadow)
    return v.kind[q] == SampleKind::Shadow;
  return v.sameImage(p, q);
}

/// Matched pixels without a Jacobian of their own: the spacing of their neighbours' positions.
void jacobiansFromNeighbours(const FrameView& from, std::vector<PixelMatch>& out)
{
  const int W = from.f.width, H = from.f.height;
  const std::size_t n = from.f.pixels.size();
#pragma omp parallel for schedule(static)
  for (std::int64_t pp = 0; pp < static_cast<std::int64_t>(n); ++pp)
  {
    const std::size_t p = static_cast<std::size_t>(pp);
    PixelMatch& m = out[p];
    if (m.kind != MatchKind::Matched || !std::isnan(m.jacobian[0]))
      continue;
    const int i = static_cast<int>(p % W), j = static_cast<int>(p / W);
    Mat2 D = Mat2::Identity();
    for (int axis = 0; axis < 2; ++axis)
    {
      auto at = [&](int s) -> const PixelMatch*
      {
        const int ii = axis == 0 ? i + s : i, jj = axis == 1 ? j + s : j;
        if (ii < 0 || ii >= W || jj < 0 || jj >= H)
          return nullptr;
        const std::size_t q = static_cast<std::size_t>(jj) * W + ii;
        return out[q].kind == MatchKind::Matched && sameImageOrShadow(from, p, q) ? &out[q]
                                                                                  : nullptr;
      };
      const PixelMatch *minus = at(-1), *plus = at(1);
      Vec2 col(axis == 0 ? 1 : 0, axis == 1 ? 1 : 0);
      if (minus && plus)
        col = 0.5 * Vec2(plus->x - minus->x, plus->y - minus->y);
      else if (plus)
        col = Vec2(plus->x - m.x, plus->y - m.y);
      else if (minus)
        col = Vec2(m.x - minus->x, m.y - minus->y);
      D.col(axis) = col;
    }
    // Written after the loop reads: other threads only read matched neighbours' positions.
    setJacobian(m, D);
  }
}

/// The pixels marked in needsField move by a push-pull extrapolation of the whole matched motion
/// field (position offset and Jacobian); where nothing matched at all, every pixel stays put.
void extrapolateMatchedField(int W, int H, const std::vector<std::uint8_t>& needsField,
                             std::vector<PixelMatch>& out)
{
  const std::size_t n = out.size();
  std::vector<float> field(n * 6, 0.0f), weight(n, 0.0f);
  for (std::size_t p = 0; p < n; ++p)
    if (out[p].kind == MatchKind::Matched)
    {
      const PixelMatch& o = out[p];
      const float vals[6] = { o.x - static_cast<float>(p % W),
                              o.y - static_cast<float>(p / W),
                              o.jacobian[0],
                              o.jacobian[1],
                              o.jacobian[2],
                              o.jacobian[3] };
      std::copy(vals, vals + 6, &field[6 * p]);
      weight[p] = 1.0f;
    }
  const bool any = pushPullFill(W, H, 6, field.data(), weight.data());
  for (std::size_t p = 0; p < n; ++p)
    if (needsField[p])
    {
      PixelMatch& m = out[p];
      if (!any) // nothing matched at all: every pixel stays where it is
      {
        m.x = static_cast<float>(p % W);
        m.y = static_cast<float>(p / W);
        m.jacobian = { { 1, 0, 0, 1 } };
        continue;
      }
      m.x = static_cast<float>(p % W) + field[6 * p];
      m.y = static_cast<float>(p / W) + field[6 * p + 1];
      for (int c = 0; c < 4; ++c)
        m.jacobian[c] = field[6 * p + 2 + c];
    }
}

/// One-sided and ambiguous pixels move as their matched neighbours do: those of the same image
/// within the radius if any, else any matched ones within it, else a push-pull extrapolation of
/// the whole matched motion field.
void extrapolateUnmatched(const FrameView& from, const MatchOptions& opt,
                          std::vector<PixelMatch>& out)
{
  const int W = from.f.width, H = from.f.height;
  const std::size_t n = from.f.pixels.size();
  auto matched = [&](std::size_t q) { return out[q].kind == MatchKind::Matched; };
  const int R = std::max(1, opt.extrapolationRadius);
  std::vector<std::uint8_t> needsField(n, 0);
  bool anyNeedsField = false;
#pragma omp parallel for schedule(dynamic, 64) reduction(|| : anyNeedsField)
  for (std::int64_t pp = 0; pp < static_cast<std::int64_t>(n); ++pp)
  {
    const std::size_t p = static_cast<std::size_t>(pp);
    if (matched(p))
      continue;
    const int i = static_cast<int>(p % W), j = static_cast<int>(p / W);
    double acc[2][7] = {};
    for (int jj = std::max(0, j - R); jj <= std::min(H - 1, j + R); ++jj)
      for (int ii = std::max(0, i - R); ii <= std::min(W - 1, i + R); ++ii)
      {
        const std::size_t q = static_cast<std::size_t>(jj) * W + ii;
        if (!matched(q))
          continue;
        const PixelMatch& o = out[q];
        const double w = 1.0 / (1.0 + (ii - i) * (ii - i) + (jj - j) * (jj - j));
        const double vals[6] = { o.x - ii,      o.y - jj,      o.jacobian[0],
                                 o.jacobian[1], o.jacobian[2], o.jacobian[3] };
        for (int set = 0; set < 2; ++set)
        {
          if (set == 0 && !sameImageOrShadow(from, p, q))
            continue;
          acc[set][6] += w;
          for (int c = 0; c < 6; ++c)
            acc[set][c] += w * vals[c];
        }
      }
    const double* a = acc[0][6] > 0 ? acc[0] : acc[1][6] > 0 ? acc[1] : nullptr;
    if (!a)
    {
      needsField[p] = 1;
      anyNeedsField = true;
      continue;
    }
    PixelMatch& m = out[p];
    m.x = static_cast<float>(i + a[0] / a[6]);
    m.y = static_cast<float>(j + a[1] / a[6]);
    for (int c = 0; c < 4; ++c)
      m.jacobian[c] = static_cast<float>(a[2 + c] / a[6]);
  }
  if (anyNeedsField)
    extrapolateMatchedField(W, H, needsField, out);
}

/// Matches every pixel of `from` into `to`.
std::vector<PixelMatch> matchOneWay(const FrameView& from, const FrameView& to,
                                    const PointIndexFactory& makeIndex, const MatchOptions& opt,
                                    const std::function<void(double)>& progress, double progress0,
                                    double progressSpan)
{
  std::vector<PixelMatch> out(from.f.pixels.size());
  {
    const TargetGroups targets(from, to, makeIndex);
    matchPixels(from, to, targets, opt, progress, progress0, progressSpan, out);
  }
  jacobiansFromNeighbours(from, out);
  extrapolateUnmatched(from, opt, out);
  return out;
}
}

Correspondence matchFrames(const FrameSamples& a, const FrameSamples& b,
                           const PointIndexFactory& index, const MatchOptions& options,
                           const std::function<void(double)>& progress)
{
  if (a.width != b.width || a.height != b.height)
  {
    std::ostringstream os;
    os << "frames of different resolutions: " << a.width << " x " << a.height << " and " << b.width
       << " x " << b.height;
    throw InvalidParameter(os.str());
  }
  if (!index)
    throw InvalidParameter("matchFrames needs a point index factory");
  if (!(options.tolerance > 0) || !(options.pathLengthTie >= 0))
    throw InvalidParameter("match tolerances must be positive");
  const FrameView va(a), vb(b);
  Correspondence c;
  c.width = a.width;
  c.height = a.height;
  c.aToB = matchOneWay(va, vb, index, options, progress, 0.0, 0.5);
  c.bToA = matchOneWay(vb, va, index, options, progress, 0.5, 0.5);
  if (progress)
    progress(1.0);
  return c;
}

const char* toString(CameraPath p)
{
  switch (p)
  {
    case CameraPath::Automatic:
      return "automatic";
    case CameraPath::Linear:
      return "linear";
    case CameraPath::Orbit:
      return "orbit";
  }
  return "?";
}

FrameParameters parametersOf(const SceneDescription& d)
{
  FrameParameters p;
  p.spacetime = d.spacetime;
  p.position = d.camera.position;
  p.focalPoint = d.camera.focalPoint;
  p.viewUp = d.camera.viewUp;
  return p;
}

void applyParameters(const FrameParameters& p, SceneDescription& d)
{
  d.spacetime = p.spacetime;
  d.camera.position = p.position;
  d.camera.focalPoint = p.focalPoint;
  d.camera.viewUp = p.viewUp;
}

FrameParameters interpolateParameters(const FrameParameters& a, const FrameParameters& b, double t,
                                      CameraPath path)
{
  requireFinite(t, "interpolation time");
  if (t == 0.0)
    return a; // the ends are the traced frames, to the bit
  if (t == 1.0)
    return b;
  auto lerp = [t](const auto& x, const auto& y) { return (1.0 - t) * x + t * y; };
  FrameParameters p;
  p.spacetime.mass = lerp(a.spacetime.mass, b.spacetime.mass);
  p.spacetime.spin = lerp(a.spacetime.spin, b.spacetime.spin);
  p.spacetime.charge = lerp(a.spacetime.charge, b.spacetime.charge);
  p.focalPoint = lerp(a.focalPoint, b.focalPoint);
  const Vec3 up = lerp(a.viewUp.normalized(), b.viewUp.normalized());
  if (!(up.norm() > 1e-9))
    throw InvalidParameter("the view-up vectors of the two frames are opposite: the one in "
                           "between is undefined");
  p.viewUp = up.normalized();
  if (path == CameraPath::Automatic)
    path = a.spacetime.mass > 0 || b.spacetime.mass > 0 ? CameraPath::Orbit : CameraPath::Linear;
  const double ra = a.position.norm(), rb = b.position.norm();
  if (path == CameraPath::Linear || ra == 0 || rb == 0)
  {
    p.position = lerp(a.position, b.position);
    return p;
  }
  const Vec3 na = a.position / ra, nb = b.position / rb;
  const double angle = std::atan2(na.cross(nb).norm(), na.dot(nb));
  Vec3 n = na;
  if (angle > 1e-12)
  {
    if (M_PI - angle < 1e-9)
      throw InvalidParameter("the two camera positions lie opposite each other about the hole: "
                             "the orbit between them is undefined (use the linear camera path)");
    n = (std::sin((1.0 - t) * angle) * na + std::sin(t * angle) * nb) / std::sin(angle);
  }
  p.position = lerp(ra, rb) * n;
  return p;
}

namespace
{
using json = nlohmann::json;

std::string shown(const json& v)
{
  std::string s = v.dump();
  return s.size() > 60 ? s.substr(0, 57) + "..." : s;
}

std::string firstDifference(const json& a, const json& b, const std::string& path)
{
  if (a.type() != b.type() && !(a.is_number() && b.is_number()))
    return path + ": " + shown(a) + " vs " + shown(b);
  if (a.is_object())
  {
    for (const auto& item : a.items())
    {
      const std::string sub = path.empty() ? item.key() : path + "." + item.key();
      if (!b.contains(item.key()))
        return sub + ": " + shown(item.value()) + " vs (absent)";
      const std::string d = firstDifference(item.value(), b.at(item.key()), sub);
      if (!d.empty())
        return d;
    }
    for (const auto& item : b.items())
      if (!a.contains(item.key()))
        return (path.empty() ? item.key() : path + "." + item.key()) + ": (absent) vs " +
               shown(item.value());
    return "";
  }
  if (a.is_array())
  {
    if (a.size() != b.size())
      return path + ": " + shown(a) + " vs " + shown(b);
    for (std::size_t k = 0; k < a.size(); ++k)
    {
      const std::string d = firstDifference(a[k], b[k], path + "[" + std::to_string(k) + "]");
      if (!d.empty())
        return d;
    }
    return "";
  }
  if (a.is_number())
    return a.get<double>() == b.get<double>() ? "" : path + ": " + shown(a) + " vs " + shown(b);
  return a == b ? "" : path + ": " + shown(a) + " vs " + shown(b);
}
}

std::string sceneDifference(const SceneDescription& a, const SceneDescription& b)
{
  auto stripped = [](const SceneDescription& d)
  {
    json j = json::parse(effectiveSceneText(d));
    // What a movie varies, and what only names or describes the scene.
    j.erase("name");
    j.erase("description");
    for (const char* k : { "mass", "spin", "charge" })
      j["spacetime"].erase(k);
    for (const char* k : { "position", "focalPoint", "viewUp" })
      j["camera"].erase(k);
    j["integrator"].erase("method");
    return j;
  };
  return firstDifference(stripped(a), stripped(b), "");
}
}
