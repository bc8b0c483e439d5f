#include "PathInterpolation.h"

#include "ErrorEstimate.h"
#include "LeaveOneOut.h"
#include "PathEdges.h"
#include "RecordHashing.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <sstream>
#include <string>
#include <utility>

namespace asrt
{
namespace
{
[[noreturn]] void invalid(const std::string& what)
{
  throw InvalidParameter("path interpolation: " + what);
}

void checkKeys(const std::vector<PathKey>& keys, double t, int width, int height)
{
  if (width <= 0 || height <= 0)
    invalid("the frame size must be positive, got " + std::to_string(width) + " x " +
            std::to_string(height));
  if (keys.size() < 2)
    invalid("at least 2 key frames are needed, got " + std::to_string(keys.size()));
  const std::size_t n = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
  for (std::size_t k = 0; k < keys.size(); ++k)
  {
    if (!keys[k].records || keys[k].records->size() != n)
      invalid("key frame " + std::to_string(k) + " has " +
              std::to_string(keys[k].records ? keys[k].records->size() : 0) +
              " records, the frame " + std::to_string(width) + " x " + std::to_string(height) +
              " has " + std::to_string(n) + " pixels");
    if (!std::isfinite(keys[k].s) || (k > 0 && !(keys[k].s > keys[k - 1].s)))
      invalid("the keys' parameters must be finite and strictly increasing (key " +
              std::to_string(k) + ")");
    const std::vector<RayRecord>& r = *keys[k].records;
    std::size_t p = 0;
    for (int j = 0; j < height; ++j)
      for (int i = 0; i < width; ++i, ++p)
        if (r[p].i != i || r[p].j != j)
          invalid("key frame " + std::to_string(k) + ": record " + std::to_string(p) +
                  " is pixel (" + std::to_string(r[p].i) + ", " + std::to_string(r[p].j) +
                  "), not (" + std::to_string(i) + ", " + std::to_string(j) + ")");
  }
  if (!(t >= keys.front().s && t <= keys.back().s))
  {
    std::ostringstream os;
    os.precision(17);
    os << "t = " << t << " lies outside the keys' range [" << keys.front().s << ", "
       << keys.back().s << "]";
    invalid(os.str());
  }
}

/// Whether a key's record can serve as a node: one ray (no edge through the pixel).
bool singleRay(const RayRecord& r)
{
  return r.raysPerPixel <= 1;
}

/// Sets `out`'s u, v and their Jacobian to the nodes' weighed by `w`: each node's u the short way
/// round from the previous node's, so that a u drifting across the seam stays one smooth function
/// of s, then wrapped into [0, 1); v clamped to [0, 1].
void interpolateSurface(const RayRecord* const* nodes, const double* w, int n, RayRecord& out)
{
  out.u = out.v = 0;
  out.dudi = out.dudj = out.dvdi = out.dvdj = 0;
  double u = nodes[0]->u;
  for (int k = 0; k < n; ++k)
  {
    const RayRecord& r = *nodes[k];
    if (k > 0)
      u += shortUDifference(r.u, nodes[k - 1]->u);
    out.u += w[k] * u;
    out.v += w[k] * r.v;
    out.dudi += w[k] * r.dudi;
    out.dudj += w[k] * r.dudj;
    out.dvdi += w[k] * r.dvdi;
    out.dvdj += w[k] * r.dvdj;
  }
  out.u -= std::floor(out.u);
  out.v = std::clamp(out.v, 0.0, 1.0);
}

/// A disagreement in (u, v) this many pixels long or less, at the pixel's footprint (its
/// Jacobian), lies within the texture filter's reach of a pixel, where the filtered colour varies
/// linearly.
constexpr double kLinearDisagreement = 0.25;

/// Whether the disagreement (du, dv) is at most `pixels` long at `r`'s footprint: the pixel
/// offset J⁻¹ (du, dv), J = ∂(u, v)/∂(i, j). False where J is singular or not finite.
bool withinFootprint(const RayRecord& r, double du, double dv, double pixels)
{
  const double det = r.dudi * r.dvdj - r.dudj * r.dvdi;
  if (!std::isfinite(det) || det == 0.0)
    return false;
  const double di = (r.dvdj * du - r.dudj * dv) / det;
  const double dj = (r.dudi * dv - r.dvdi * du) / det;
  return di * di + dj * dj <= pixels * pixels;
}

/// The estimate of a prediction `out` from its lower order `lower`: the squared colour difference
/// between them, or more where the texture changes within the orders' disagreement about (u, v).
/// Two predictions may land on like colours while a small bright feature (a star) lies between or
/// beside them; a ray sweeping across it between keys is missed by both. So the colour is also
/// sampled one disagreement further on, and one to either side of it. Where the disagreement is
/// a small part of the pixel's footprint, the filtered colour is linear across it: the sample
/// further on then differs from the prediction as the lower order does, and the two sides alike,
/// so one side is sampled alone.
float predictionError(const Scene& scene, const RayRecord& out, const RayRecord& lower)
{
  const Color lowerColor = shadePrediction(scene, lower);
  float estimate = colorError2(out.color, lowerColor);
  if (out.objectId < 0)
    return estimate;
  const double du = shortUDifference(out.u, lower.u), dv = out.v - lower.v;
  const TextureFootprint footprint{ out.dudi, out.dvdi, out.dudj, out.dvdj };
  const double offsets[3][2] = { { -dv, du }, { du, dv }, { dv, -du } };
  const int sampled = withinFootprint(out, du, dv, kLinearDisagreement) ? 1 : 3;
  for (int k = 0; k < sampled; ++k)
  {
    const double(&d)[2] = offsets[k];
    const double u = out.u + d[0];
    const double v = std::clamp(out.v + d[1], 0.0, 1.0);
    const Color c = scene.shadeFootprint(out.objectId, u - std::floor(u), v, footprint);
    estimate = std::max(estimate, colorError2(out.color, c));
  }
  return estimate;
}

/// What predictRecord gives of the fields a prediction is shaded from (object, ending, u, v and
/// their Jacobian), the same values, and nothing else: the lower order an estimate is measured by.
RayRecord predictSurface(const RayRecord* const* nodes, const double* s, int n, double t)
{
  double w[4];
  lagrangeWeights(s, n, t, w);
  RayRecord out;
  out.objectId = nodes[0]->objectId;
  out.termination = nodes[0]->termination;
  interpolateSurface(nodes, w, n, out);
  return out;
}

/// The keys a prediction of one pixel at t between the inner pair (a, a + 1) runs through,
/// [first, last]: the inner pair and, on either side, the outer key (a − 1, a + 2) whose record
/// `follows(outer, inner)` the record of the inner key beside it (ends alike with it).
/// At an end of the keys, where one side has no outer key, the second key beyond on the other side
/// (a + 3 or a − 2) where it follows the first: `beyond`, or none. It does not join the
/// prediction (a cubic through keys all on one side of t fared worse than the quadratic on the
/// orbits, 0.3 dB on the Kerr disk's) but measures its error: the difference to the cubic through
/// all 4 is the quadratic's own error to the next order, where the difference to the line ranks
/// its error poorly (on the spin ramp, whose first and last intervals' pixels are mostly
/// quadratic, the worst frame's rank correlation before rounding rose from 0.80 to 0.84).
struct NodeRange
{
  std::size_t first = 0, last = 0;
  std::optional<std::size_t> beyond;
};
template<typename Follows>
NodeRange nodeRange(std::size_t keys, std::size_t a, Follows&& follows)
{
  const bool left = a > 0 && follows(a - 1, a);
  const bool right = a + 2 < keys && follows(a + 2, a + 1);
  NodeRange r;
  r.first = left ? a - 1 : a;
  r.last = right ? a + 2 : a + 1;
  if (a == 0 && right && a + 3 < keys && follows(a + 3, a + 2))
    r.beyond = a + 3;
  if (a + 2 == keys && left && a >= 2 && follows(a - 2, a - 1))
    r.beyond = a - 2;
  return r;
}

/// One pixel's records along the path, in order of s, that its prediction may run through: the
/// keys' (KeyNodes), or the keys' and those of frames traced in part that hold the pixel
/// (SampledNodes).
struct KeyNodes
{
  const std::vector<PathKey>& keys;
  std::size_t p;
  std::size_t size() const { return keys.size(); }
  double s(std::size_t k) const { return keys[k].s; }
  const RayRecord& record(std::size_t k) const { return (*keys[k].records)[p]; }
};

/// At most this many records on either side of t join a pixel's chain of sampled nodes: the inner
/// one, the outer one and the one beyond (nodeRange).
constexpr std::size_t kSideNodes = 3;

struct SampledNodes
{
  std::size_t count = 0;
  double at[2 * kSideNodes];
  const RayRecord* records[2 * kSideNodes];
  std::size_t size() const { return count; }
  double s(std::size_t k) const { return at[k]; }
  const RayRecord& record(std::size_t k) const { return *records[k]; }
};

/// The nodes of a pixel's prediction from the inner pair (a, a + 1) of its records `chain`
/// (nodeRange: the outer records whose single ray ends as the inner one's beside it), into
/// `nodes` and `s`; returns the range.
template<typename Nodes>
NodeRange pixelNodes(const Nodes& chain, std::size_t a, const RayRecord* (&nodes)[4],
                     double (&s)[4], int& n)
{
  const NodeRange range = nodeRange(chain.size(), a,
                                    [&](std::size_t outer, std::size_t beside)
                                    {
                                      const RayRecord& r = chain.record(outer);
                                      return singleRay(r) && endAlike(r, chain.record(beside));
                                    });
  n = 0;
  for (std::size_t k = range.first; k <= range.last; ++k)
  {
    nodes[n] = &chain.record(k);
    s[n++] = chain.s(k);
  }
  return range;
}

/// The prediction of one pixel from the inner pair (a, a + 1) of its records `chain` and the
/// outer ones that end alike (nodeRange); sets `estimate` as the header says.
template<typename Nodes>
RayRecord predictPixel(const Nodes& chain, std::size_t a, double t, const Scene& scene,
                       PathMethod& method, float& estimate, bool withEstimate = true)
{
  const RayRecord* inner[2] = { &chain.record(a), &chain.record(a + 1) };
  const RayRecord* nodes[4];
  double s[4];
  int n = 0;
  const NodeRange range = pixelNodes(chain, a, nodes, s, n);
  const std::size_t first = range.first, last = range.last;
  const bool left = first < a;
  const bool right = last > a + 1;
  RayRecord out = predictRecord(nodes, s, n, t);
  out.color = shadePrediction(scene, out);
  estimate = 0.0f;
  if (!withEstimate)
  {
    method = n == 4 ? PathMethod::Cubic : n == 3 ? PathMethod::Quadratic : PathMethod::Linear;
    return out;
  }
  if (n == 2)
  {
    // One order lower is the nearer record itself: its (u, v) shows how far the pixel moved on
    // the texture, and the records' colour step what lies along the way.
    method = PathMethod::Linear;
    const RayRecord& nearer = t - chain.s(a) <= chain.s(a + 1) - t ? *inner[0] : *inner[1];
    estimate =
      std::max(colorError2(inner[0]->color, inner[1]->color), predictionError(scene, out, nearer));
    return out;
  }
  method = n == 4 ? PathMethod::Cubic : PathMethod::Quadratic;
  if (range.beyond)
  {
    // At an end of the chain: the quadratic against the cubic through the record beyond too.
    const RayRecord* all[4];
    double at[4];
    const int shift = *range.beyond < first ? 1 : 0;
    all[shift ? 0 : 3] = &chain.record(*range.beyond);
    at[shift ? 0 : 3] = chain.s(*range.beyond);
    for (int k = 0; k < 3; ++k)
    {
      all[k + shift] = nodes[k];
      at[k + shift] = s[k];
    }
    estimate = predictionError(scene, out, predictSurface(all, at, 4, t));
    return out;
  }
  // One order lower: without the outer node farther from t (the left one on a tie).
  const bool dropLeft = left && (!right || t - chain.s(first) >= chain.s(last) - t);
  const int offset = dropLeft ? 1 : 0;
  const RayRecord lower = predictSurface(nodes + offset, s + offset, n - 1, t);
  estimate = predictionError(scene, out, lower);
  return out;
}

RayRecord predictPixel(const std::vector<PathKey>& keys, std::size_t a, std::size_t p, double t,
                       const Scene& scene, PathMethod& method, float& estimate,
                       bool withEstimate = true)
{
  return predictPixel(KeyNodes{ keys, p }, a, t, scene, method, estimate, withEstimate);
}

/// predictPixel's colour alone: the surface its nodes predict (predictSurface), shaded.
Color predictedColour(const std::vector<PathKey>& keys, std::size_t a, std::size_t p, double t,
                      const Scene& scene)
{
  const RayRecord* nodes[4];
  double s[4];
  int n = 0;
  pixelNodes(KeyNodes{ keys, p }, a, nodes, s, n);
  return shadePrediction(scene, predictSurface(nodes, s, n, t));
}

/// The largest squared colour difference between pixel p of a key and its 4 neighbours there: what
/// an edge through the pixel that moves by a pixel between the keys can change its colour by. The
/// blend of an edge pixel's colours follows the edge's coverage only while the edge stays inside
/// it; keys far apart let it move further.
float edgeContrast(const std::vector<RayRecord>& key, std::size_t p, int width, int height)
{
  const int i = static_cast<int>(p % width), j = static_cast<int>(p / width);
  const int di[4] = { -1, 1, 0, 0 }, dj[4] = { 0, 0, -1, 1 };
  float contrast = 0.0f;
  for (int k = 0; k < 4; ++k)
  {
    const int x = i + di[k], y = j + dj[k];
    if (x >= 0 && x < width && y >= 0 && y < height)
      contrast = std::max(
        contrast, colorError2(key[p].color, key[static_cast<std::size_t>(y) * width + x].color));
  }
  return contrast;
}

/// A pixel that a key supersampled (an edge runs through it) but whose topology holds between the
/// keys. Its colour is the average over the edge's two sides: a share α on the centre ray's side,
/// whose colour C_c is the centre ray's, and 1 − α on the other, of colour C_o. The centre ray is
/// predicted and re-shaded as any pixel's, and the rest, the key's colour less its centre ray's
/// shade ((1 − α)(C_o − C_c)), interpolated: where a texture moves under the centre's side (an
/// orbit, with the edges in place) only the other side's share of its motion is left to the
/// interpolation, not the whole of it; where the edge moves, the rest follows α as the colour
/// itself would. The record is the centre ray's prediction, colour aside.
RayRecord predictEdgePixel(const std::vector<PathKey>& keys, std::size_t a, std::size_t p, double t,
                           int width, int height, const Scene& scene, PathMethod& method,
                           float& estimate, bool withEstimate = true)
{
  const RayRecord& ra = (*keys[a].records)[p];
  const RayRecord& rb = (*keys[a + 1].records)[p];
  const NodeRange range =
    nodeRange(keys.size(), a,
              [&](std::size_t outer, std::size_t beside)
              { return endAlike((*keys[outer].records)[p], (*keys[beside].records)[p]); });
  // The nodes, and at an end of the keys the key beyond before or after them: n of them from
  // `offset` on predict, all `count` measure the estimate.
  const std::size_t first =
    range.beyond && *range.beyond < range.first ? *range.beyond : range.first;
  const std::size_t last = range.beyond && *range.beyond > range.last ? *range.beyond : range.last;
  const int offset = static_cast<int>(range.first - first);
  const bool left = range.first < a;
  const bool right = range.last > a + 1;
  const RayRecord* nodes[4];
  double s[4], w[4];
  Color rest[4];
  int count = 0;
  for (std::size_t k = first; k <= last; ++k)
  {
    nodes[count] = &(*keys[k].records)[p];
    rest[count] = nodes[count]->color - shadePrediction(scene, *nodes[count]);
    s[count++] = keys[k].s;
  }
  const int n = static_cast<int>(range.last - range.first) + 1;
  // The prediction through the nodes from `offset` on, `count` of them.
  auto blend = [&](int offset, int count)
  {
    RayRecord centre = predictRecord(nodes + offset, s + offset, count, t);
    lagrangeWeights(s + offset, count, t, w);
    Color out = shadePrediction(scene, centre);
    for (int k = 0; k < count; ++k)
      out += w[k] * rest[offset + k];
    centre.color = out.cwiseMax(0.0).cwiseMin(1.0);
    return centre;
  };
  const std::size_t nearerKey = t - keys[a].s <= keys[a + 1].s - t ? a : a + 1;
  RayRecord out = blend(offset, n);
  // The record is the centre ray's prediction at t; its rays are the nearer key's (the
  // anti-aliasing an edge pixel took).
  out.raysPerPixel = (*keys[nearerKey].records)[p].raysPerPixel;
  method = PathMethod::EdgeBlend;
  estimate = 0.0f;
  if (!withEstimate)
    return out;
  if (n == 2)
  {
    estimate = std::max(colorError2(ra.color, rb.color),
                        edgeContrast(*keys[nearerKey].records, p, width, height));
    return out;
  }
  // One order lower: without the outer node farther from t; at an end of the keys one higher,
  // through the key beyond too.
  const bool dropLeft = left && (!right || t - keys[range.first].s >= keys[range.last].s - t);
  const RayRecord other = range.beyond ? blend(0, count) : blend(dropLeft ? 1 : 0, n - 1);
  // An edge's colour follows its coverage of the pixel, which polynomials in s follow only
  // roughly: the keys' colour step bounds what the edge's motion can change in between. The
  // neighbours' contrast (a move by a whole pixel) is left out here: the outer keys' centre rays
  // end as the inner keys' do, so the edge stayed within reach of the pixel over 3 or 4 keys. On
  // the Kerr disk, whose edges barely move, it made the edge blends 2–4 % of the error and 50–60 %
  // of the estimate, ranked above the moved edges that held over 90 % of it.
  estimate = std::max(colorError2(out.color, other.color), colorError2(ra.color, rb.color));
  return out;
}

}

namespace
{

/// Per pixel, whether the inner keys' records of it do not end alike.
std::vector<std::uint8_t> disagreements(const std::vector<RayRecord>& ka,
                                        const std::vector<RayRecord>& kb)
{
  std::vector<std::uint8_t> disagree(ka.size(), 0);
  for (std::size_t p = 0; p < ka.size(); ++p)
    disagree[p] = !endAlike(ka[p], kb[p]);
  return disagree;
}

/// Whether pixel (i, j) or one of its 8 neighbours is one the inner keys disagree on: an edge
/// that moved between the keys may cross it at t.
bool nearDisagreement(const std::vector<std::uint8_t>& disagree, int i, int j, int width,
                      int height)
{
  for (int dj = -1; dj <= 1; ++dj)
    for (int di = -1; di <= 1; ++di)
    {
      const int x = i + di, y = j + dj;
      if (x >= 0 && x < width && y >= 0 && y < height &&
          disagree[static_cast<std::size_t>(y) * width + x])
        return true;
    }
  return false;
}

void checkSamples(const std::vector<std::shared_ptr<const PathSamples>>& samples, int width,
                  int height)
{
  const std::int64_t n = static_cast<std::int64_t>(width) * height;
  for (std::size_t k = 0; k < samples.size(); ++k)
  {
    const std::string which = "sample frame " + std::to_string(k);
    if (!samples[k])
      invalid(which + " is null");
    const PathSamples& f = *samples[k];
    if (!std::isfinite(f.s))
      invalid(which + ": its parameter s must be finite");
    if (f.records.size() != f.pixels.size())
      invalid(which + " has " + std::to_string(f.records.size()) + " records for " +
              std::to_string(f.pixels.size()) + " pixels");
    for (std::size_t r = 0; r < f.pixels.size(); ++r)
    {
      const std::int32_t p = f.pixels[r];
      if (p < 0 || p >= n || (r > 0 && p <= f.pixels[r - 1]))
        invalid(which + ": its pixels must be strictly ascending indices of the " +
                std::to_string(width) + " x " + std::to_string(height) + " frame (entry " +
                std::to_string(r) + " is " + std::to_string(p) + ")");
      if (f.records[r].i != p % width || f.records[r].j != p / width)
        invalid(which + ": record " + std::to_string(r) + " is pixel (" +
                std::to_string(f.records[r].i) + ", " + std::to_string(f.records[r].j) +
                "), not pixel " + std::to_string(p) + "'s");
    }
  }
}

/// A frame a pixel's chain may draw on: a key (every pixel) or a frame traced in part.
struct ChainSource
{
  double s = 0;
  const std::vector<RayRecord>* key = nullptr;
  const PathSamples* samples = nullptr;
  /// Pixel p's record here, or null where this frame did not trace it.
  const RayRecord* record(std::size_t p) const
  {
    if (key)
      return &(*key)[p];
    const auto it =
      std::lower_bound(samples->pixels.begin(), samples->pixels.end(), std::int32_t(p));
    return it != samples->pixels.end() && *it == std::int32_t(p)
             ? &samples->records[static_cast<std::size_t>(it - samples->pixels.begin())]
             : nullptr;
  }
};

/// The keys and the samples strictly between the inner keys (a, a + 1) other than at t, in order
/// of s; `below` is the number of them before t.
std::vector<ChainSource> chainSources(
  const std::vector<PathKey>& keys, std::size_t a, double t,
  const std::vector<std::shared_ptr<const PathSamples>>& samples, std::size_t& below)
{
  std::vector<ChainSource> sources;
  for (const PathKey& key : keys)
    sources.push_back({ key.s, key.records, nullptr });
  for (const auto& f : samples)
    if (f->s > keys[a].s && f->s < keys[a + 1].s && f->s != t)
      sources.push_back({ f->s, nullptr, f.get() });
  // Two samples at one s: the first given stands (a stable sort keeps them in order).
  std::stable_sort(sources.begin(), sources.end(),
                   [](const ChainSource& x, const ChainSource& y) { return x.s < y.s; });
  sources.erase(std::unique(sources.begin(), sources.end(),
                            [](const ChainSource& x, const ChainSource& y) { return x.s == y.s; }),
                sources.end());
  below = static_cast<std::size_t>(std::lower_bound(sources.begin(), sources.end(), t,
                                                    [](const ChainSource& x, double v)
                                                    { return x.s < v; }) -
                                   sources.begin());
  return sources;
}

/// Pixel p predicted from its chain (the header's Chains paragraph), where its chain vouches for
/// it: the records of `sources` that hold it, at most kSideNodes on either side of t. `retrace`
/// marks the pixels the keys cannot vouch for.
bool predictFromChain(const std::vector<ChainSource>& sources, std::size_t below, std::size_t p,
                      int width, int height, const std::vector<std::uint8_t>& retrace, double t,
                      const Scene& scene, bool withEstimate, RayRecord& out, PathMethod& method,
                      float& estimate)
{
  SampledNodes lower, upper; // nearest first
  std::size_t from[2] = { 0, 0 };
  for (std::size_t k = below; k-- > 0 && lower.count < kSideNodes;)
    if (const RayRecord* r = sources[k].record(p))
    {
      if (lower.count == 0)
        from[0] = k;
      lower.at[lower.count] = sources[k].s;
      lower.records[lower.count++] = r;
    }
  for (std::size_t k = below; k < sources.size() && upper.count < kSideNodes; ++k)
    if (const RayRecord* r = sources[k].record(p))
    {
      if (upper.count == 0)
        from[1] = k;
      upper.at[upper.count] = sources[k].s;
      upper.records[upper.count++] = r;
    }
  if (lower.count == 0 || upper.count == 0 || (sources[from[0]].key && sources[from[1]].key))
    return false; // the keys themselves are the inner pair: they did not vouch for it
  const RayRecord &lo = *lower.records[0], &hi = *upper.records[0];
  if (!singleRay(lo) || !singleRay(hi) || !endAlike(lo, hi))
    return false;
  const int i = static_cast<int>(p % width), j = static_cast<int>(p / width);
  for (int dj = -1; dj <= 1; ++dj)
    for (int di = -1; di <= 1; ++di)
    {
      const int x = i + di, y = j + dj;
      if ((di == 0 && dj == 0) || x < 0 || x >= width || y < 0 || y >= height)
        continue;
      const std::size_t q = static_cast<std::size_t>(y) * width + x;
      if (!retrace[q])
        continue;
      const RayRecord *qlo = sources[from[0]].record(q), *qhi = sources[from[1]].record(q);
      if (!qlo || !qhi || !endAlike(*qlo, *qhi))
        return false;
    }
  SampledNodes chain;
  for (std::size_t k = lower.count; k-- > 0;)
  {
    chain.at[chain.count] = lower.at[k];
    chain.records[chain.count++] = lower.records[k];
  }
  for (std::size_t k = 0; k < upper.count; ++k)
  {
    chain.at[chain.count] = upper.at[k];
    chain.records[chain.count++] = upper.records[k];
  }
  out = predictPixel(chain, lower.count - 1, t, scene, method, estimate, withEstimate);
  return true;
}

/// The pixels the inner keys (a, a + 1) cannot vouch for, predicted from their chains where those
/// vouch for them (predictFromChain); marks them in `chained`.
void predictChains(const std::vector<PathKey>& keys, std::size_t a, double t, const Scene& scene,
                   const PathOptions& options, PathFrame& f, std::vector<std::uint8_t>& chained)
{
  std::size_t below = 0;
  const std::vector<ChainSource> sources = chainSources(keys, a, t, options.samples, below);
  if (sources.size() == keys.size())
    return; // no sample between the inner keys
  const std::size_t n = f.method.size();
  std::vector<std::uint8_t> retrace(n, 0);
  for (std::size_t p = 0; p < n; ++p)
    retrace[p] = f.method[p] == static_cast<std::uint8_t>(PathMethod::Retrace);
#pragma omp parallel for schedule(dynamic, 4)
  for (int j = 0; j < f.height; ++j)
    for (int i = 0; i < f.width; ++i)
    {
      const std::size_t p = static_cast<std::size_t>(j) * f.width + i;
      if (!retrace[p])
        continue;
      RayRecord out;
      PathMethod m;
      float e = 0.0f;
      if (predictFromChain(sources, below, p, f.width, f.height, retrace, t, scene,
                           options.estimates, out, m, e))
      {
        f.records[p] = out;
        f.estimate[p] = e;
        f.method[p] = static_cast<std::uint8_t>(m);
        chained[p] = 1;
      }
    }
}

/// The pixels left to be re-traced, predicted where the keys' moved scene points cover them and
/// the ways of predicting them give a finite estimate (PathEdges.h).
void predictEdges(const std::vector<PathKey>& keys, std::size_t a, double t, const Scene& scene,
                  const PointIndexFactory& index, const std::vector<RayRecord>& own,
                  const std::vector<std::uint8_t>& hasOwn, bool hedged, bool hedgeNearShadow,
                  PathMatchCache* cache, const SpacetimeAlongPath& along, double residualShare,
                  PathFrame& f)
{
  std::vector<std::int32_t> pixels;
  std::vector<const RayRecord*> perPixel;
  for (std::size_t p = 0; p < f.method.size(); ++p)
    if (f.method[p] == static_cast<std::uint8_t>(PathMethod::Retrace))
    {
      pixels.push_back(static_cast<std::int32_t>(p));
      perPixel.push_back(hasOwn[p] ? &own[p] : nullptr);
    }
  const std::vector<MovedEdgePixel> moved =
    predictMovedEdges(keys, a, t, f.width, f.height, scene, index, pixels, perPixel, hedged,
                      hedgeNearShadow, cache, along, residualShare);
  for (std::size_t k = 0; k < pixels.size(); ++k)
    if (moved[k].covered && std::isfinite(moved[k].estimate))
    {
      const std::size_t p = static_cast<std::size_t>(pixels[k]);
      f.records[p] = moved[k].record;
      f.estimate[p] = moved[k].estimate;
      f.method[p] = static_cast<std::uint8_t>(moved[k].oneSurface ? PathMethod::MovedSurface
                                                                  : PathMethod::MovedEdge);
    }
}
}

std::uint64_t matchingFingerprint(const std::vector<RayRecord>& records)
{
  std::uint64_t h = mixWord(0x9e3779b97f4a7c15ULL, records.size());
  for (const RayRecord& r : records)
  {
    h = mixWord(h, (static_cast<std::uint64_t>(static_cast<std::uint32_t>(r.i)) << 32) |
                     static_cast<std::uint32_t>(r.j));
    h = mixWord(h, (static_cast<std::uint64_t>(static_cast<std::uint32_t>(r.objectId)) << 32) |
                     (static_cast<std::uint64_t>(static_cast<std::uint32_t>(r.imageOrder)) << 8) |
                     static_cast<std::uint64_t>(r.termination));
    for (double x : { r.hitPoint.x(), r.hitPoint.y(), r.hitPoint.z(), r.u, r.v, r.dudi, r.dudj,
                      r.dvdi, r.dvdj, r.affineLength, r.color.x(), r.color.y(), r.color.z(),
                      r.direction.x(), r.direction.y(), r.direction.z() })
      h = mixWord(h, bitsOf(x));
  }
  return h;
}

PathMatchCache::PathMatchCache(std::size_t capacity)
  : Kept(capacity)
{
}

std::shared_ptr<const Correspondence> PathMatchCache::matches(
  std::uint64_t a, std::uint64_t b, const std::function<Correspondence()>& match)
{
  // Matched outside the lock: another thread may match the same pair meanwhile, to the same
  // correspondence.
  return this->Kept.get({ a, b }, match);
}

std::uint64_t keyFingerprint(const PathKey& key)
{
  return key.fingerprint != 0 ? key.fingerprint : matchingFingerprint(*key.records);
}

std::size_t PathMatchCache::made() const
{
  return this->Kept.made();
}

const char* toString(PathMethod m)
{
  switch (m)
  {
    case PathMethod::Key:
      return "key";
    case PathMethod::Cubic:
      return "cubic";
    case PathMethod::Quadratic:
      return "quadratic";
    case PathMethod::Linear:
      return "linear";
    case PathMethod::Retrace:
      return "retrace";
    case PathMethod::Retraced:
      return "retraced";
    case PathMethod::EdgeBlend:
      return "edge";
    case PathMethod::MovedEdge:
      return "moved";
    case PathMethod::MovedSurface:
      return "msurface";
  }
  return "unknown";
}

std::vector<std::size_t> PathFrame::counts() const
{
  std::vector<std::size_t> c(kPathMethodCount, 0);
  for (std::uint8_t m : this->method)
    ++c[std::min<std::size_t>(m, kPathMethodCount - 1)];
  return c;
}

void lagrangeWeights(const double* s, int n, double t, double* w)
{
  for (int k = 0; k < n; ++k)
  {
    double num = 1.0, den = 1.0;
    for (int m = 0; m < n; ++m)
    {
      if (m == k)
        continue;
      num *= t - s[m];
      den *= s[k] - s[m];
    }
    w[k] = num / den;
  }
}

bool endAlike(const RayRecord& a, const RayRecord& b)
{
  auto clean = [](Termination e) {
    return e == Termination::Escaped || e == Termination::Captured || e == Termination::HitObject;
  };
  return clean(a.termination) && sameSurface(surfaceOf(a), surfaceOf(b));
}

RayRecord predictRecord(const RayRecord* const* nodes, const double* s, int n, double t)
{
  double w[4];
  lagrangeWeights(s, n, t, w);
  RayRecord out = *nodes[0];
  out.origin = out.direction = out.hitPoint = out.hitNormal = Vec3::Zero();
  out.momentum = Vec4::Zero();
  out.affineLength = out.winding = out.chordError = out.maxAbsH = 0;
  out.steps = 0;
  out.raysPerPixel = 1;
  interpolateSurface(nodes, w, n, out);
  for (int k = 0; k < n; ++k)
  {
    const RayRecord& r = *nodes[k];
    out.origin += w[k] * r.origin;
    out.direction += w[k] * r.direction;
    out.momentum += w[k] * r.momentum;
    out.hitPoint += w[k] * r.hitPoint;
    out.hitNormal += w[k] * r.hitNormal;
    out.affineLength += w[k] * r.affineLength;
    out.winding += w[k] * r.winding;
    out.maxAbsH = std::max(out.maxAbsH, r.maxAbsH);
  }
  if (out.direction.norm() > 0)
    out.direction.normalize();
  if (out.hitNormal.norm() > 0)
    out.hitNormal.normalize();
  out.imageOrder = static_cast<std::int32_t>(std::floor(out.winding / M_PI));
  return out;
}

Color shadePrediction(const Scene& scene, const RayRecord& r)
{
  return r.objectId >= 0
           ? scene.shadeFootprint(r.objectId, r.u, r.v, { r.dudi, r.dvdi, r.dudj, r.dvdj })
           : scene.endColor(r.termination);
}

PathFrame interpolateAlongPath(const std::vector<PathKey>& keys, double t, int width, int height,
                               const Scene& scene, const PathOptions& options)
{
  checkKeys(keys, t, width, height);
  checkSamples(options.samples, width, height);
  if (options.movedEdges && !options.pointIndex)
    invalid("PathOptions::pointIndex is empty: moved edges need a point index");
  if (!(options.keyResidualShare >= 0.0 && options.keyResidualShare <= 1.0))
    invalid("PathOptions::keyResidualShare must lie in [0, 1], got " +
            std::to_string(options.keyResidualShare));
  PathFrame f;
  f.width = width;
  f.height = height;
  f.t = t;
  const std::size_t n = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
  // The inner pair (a, a + 1) brackets t.
  std::size_t a = 0;
  while (a + 2 < keys.size() && keys[a + 1].s <= t)
    ++a;
  for (const std::size_t k : { a, a + 1 })
    if (keys[k].s == t)
    {
      f.records = *keys[k].records;
      f.estimate.assign(n, 0.0f);
      f.method.assign(n, static_cast<std::uint8_t>(PathMethod::Key));
      return f;
    }
  const std::vector<RayRecord>& ka = *keys[a].records;
  const std::vector<RayRecord>& kb = *keys[a + 1].records;
  const bool nearerA = t - keys[a].s <= keys[a + 1].s - t;
  const std::vector<std::uint8_t> disagree = disagreements(ka, kb);
  f.records.resize(n);
  f.estimate.resize(n);
  f.method.resize(n);
  for (int k = 0; k < 2; ++k)
  {
    const std::vector<RayRecord>& key = k == 0 ? ka : kb;
    f.innerKeys[k].resize(n);
    for (std::size_t p = 0; p < n; ++p)
      f.innerKeys[k][p] = surfaceOf(key[p]);
  }
  // Per pixel near a disagreement that the inner keys agree on, its own prediction, which the
  // moved edge is held against (flag 1: there is one).
  std::vector<RayRecord> own;
  std::vector<std::uint8_t> hasOwn;
  if (options.movedEdges)
  {
    own.resize(n);
    hasOwn.assign(n, 0);
  }
  const float unknown = std::numeric_limits<float>::infinity();
#pragma omp parallel for schedule(dynamic, 4)
  for (int j = 0; j < height; ++j)
    for (int i = 0; i < width; ++i)
    {
      const std::size_t p = static_cast<std::size_t>(j) * width + i;
      if (nearDisagreement(disagree, i, j, width, height))
      {
        f.records[p] = nearerA ? ka[p] : kb[p];
        f.estimate[p] = unknown;
        f.method[p] = static_cast<std::uint8_t>(PathMethod::Retrace);
        if (options.movedEdges && !disagree[p] && singleRay(ka[p]) && singleRay(kb[p]))
        {
          PathMethod m;
          float e;
          own[p] = predictPixel(keys, a, p, t, scene, m, e);
          hasOwn[p] = 1;
        }
        continue;
      }
      PathMethod m;
      if (!singleRay(ka[p]) || !singleRay(kb[p]))
        f.records[p] = predictEdgePixel(keys, a, p, t, width, height, scene, m, f.estimate[p],
                                        options.estimates);
      else
        f.records[p] = predictPixel(keys, a, p, t, scene, m, f.estimate[p], options.estimates);
      f.method[p] = static_cast<std::uint8_t>(m);
    }
  std::vector<std::uint8_t> chained; // pixels predicted from their chains, not weighed
  if (!options.samples.empty())
  {
    chained.assign(n, 0);
    predictChains(keys, a, t, scene, options, f, chained);
  }
  // The kept correspondences and leave-one-out errors are both looked up by the keys'
  // fingerprints: each key's made once here, where the caller did not give it.
  const bool weighed = options.leaveOneOut && options.estimates; // the weights weigh the estimates
  std::vector<PathKey> keyed = keys;
  if ((options.movedEdges && options.matchCache) || (weighed && options.leaveOneOutCache))
    for (PathKey& key : keyed)
      key.fingerprint = keyFingerprint(key);
  if (options.movedEdges)
    predictEdges(keyed, a, t, scene, options.pointIndex, own, hasOwn, options.hedgeMovedEdges,
                 options.hedgeNearShadow, options.matchCache.get(), options.spacetimeAt,
                 options.keyResidualShare, f);
  if (weighed)
  {
    const std::vector<float> L = leaveOneOutError(keyed, t, width, height, scene, options);
    weighByLeaveOneOut(f, L, chained);
    f.leaveOneOutWeighed = !L.empty();
  }
  return f;
}

std::vector<Color> interpolatedColours(const std::vector<PathKey>& keys, double t, int width,
                                       int height, const Scene& scene)
{
  checkKeys(keys, t, width, height);
  const std::size_t n = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
  std::size_t a = 0;
  while (a + 2 < keys.size() && keys[a + 1].s <= t)
    ++a;
  std::vector<Color> colours(n);
  for (const std::size_t k : { a, a + 1 })
    if (keys[k].s == t)
    {
      for (std::size_t p = 0; p < n; ++p)
        colours[p] = (*keys[k].records)[p].color;
      return colours;
    }
  const std::vector<RayRecord>& ka = *keys[a].records;
  const std::vector<RayRecord>& kb = *keys[a + 1].records;
  const bool nearerA = t - keys[a].s <= keys[a + 1].s - t;
  const std::vector<std::uint8_t> disagree = disagreements(ka, kb);
  // interpolateAlongPath's loop, its records' colours alone: a pixel near a disagreement keeps
  // the nearer key's record, the others are predicted (the surface alone, which is what the
  // shading reads: predictSurface gives predictRecord's values of those fields).
#pragma omp parallel for schedule(dynamic, 4)
  for (int j = 0; j < height; ++j)
    for (int i = 0; i < width; ++i)
    {
      const std::size_t p = static_cast<std::size_t>(j) * width + i;
      if (nearDisagreement(disagree, i, j, width, height))
      {
        colours[p] = nearerA ? ka[p].color : kb[p].color;
        continue;
      }
      PathMethod m;
      float e;
      colours[p] = !singleRay(ka[p]) || !singleRay(kb[p])
                     ? predictEdgePixel(keys, a, p, t, width, height, scene, m, e, false).color
                     : predictedColour(keys, a, p, t, scene);
    }
  return colours;
}

}
