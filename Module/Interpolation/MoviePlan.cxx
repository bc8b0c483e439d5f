#include "MoviePlan.h"

#include "AsrtTypes.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

namespace asrt
{
const char* toString(FrameMethod m)
{
  switch (m)
  {
    case FrameMethod::Reused:
      return "reused";
    case FrameMethod::Key:
      return "key";
    case FrameMethod::Traced:
      return "traced";
    case FrameMethod::Interpolated:
      return "interpolated";
  }
  return "?";
}

double MovieCostModel::wholeRays(double s) const
{
  if (this->wholeRaysAt)
  {
    const double rays = this->wholeRaysAt(s);
    if (rays > 0 && std::isfinite(rays))
      return rays;
  }
  return this->frameRays;
}

double MovieCostModel::interpolatedRays(double s, double share) const
{
  if (!(share >= 0 && share < 1))
    return std::numeric_limits<double>::quiet_NaN();
  double retrace = this->retraceRaysAt ? this->retraceRaysAt(s, share) : -1.0;
  if (!(retrace >= 0 && std::isfinite(retrace)))
    retrace = share * (this->retraceRays > 0 ? this->retraceRays : this->frameRays);
  return retrace + this->interpolationRays;
}

MovieCostModel MovieCostPrior::model(double pixels, const RetraceShare& share) const
{
  MovieCostModel m;
  m.frameRays = pixels * this->wholeRaysPerPixel;
  m.retraceRays = pixels;
  const double edge = pixels * this->edgeRaysPerPixel;
  m.retraceRaysAt = [pixels, edge](double, double share) { return share * pixels + edge; };
  m.interpolationRays = pixels * this->interpolationRaysPerPixel;
  m.retraceShare = share;
  return m;
}

std::vector<int> MoviePlan::keys() const
{
  std::vector<int> k;
  for (std::size_t f = 0; f < this->frames.size(); ++f)
    if (this->frames[f].method != FrameMethod::Interpolated)
      k.push_back(static_cast<int>(f));
  return k;
}

namespace
{
void checkInput(const std::vector<double>& s, const std::vector<bool>& stored,
                const MovieCostModel& model)
{
  if (s.empty())
    throw InvalidParameter("movie plan: no frames");
  if (!stored.empty() && stored.size() != s.size())
    throw InvalidParameter("movie plan: " + std::to_string(stored.size()) + " stored flags for " +
                           std::to_string(s.size()) + " frames");
  if (!(model.frameRays > 0 && std::isfinite(model.frameRays)))
  {
    std::ostringstream os;
    os << "movie plan: frameRays must be positive and finite, got " << model.frameRays;
    throw InvalidParameter(os.str());
  }
  if (!(model.retraceRays >= 0 && std::isfinite(model.retraceRays)))
  {
    std::ostringstream os;
    os << "movie plan: retraceRays must be finite and not negative, got " << model.retraceRays;
    throw InvalidParameter(os.str());
  }
  if (!(model.interpolationRays >= 0 && std::isfinite(model.interpolationRays)))
  {
    std::ostringstream os;
    os << "movie plan: interpolationRays must be finite and not negative, got "
       << model.interpolationRays;
    throw InvalidParameter(os.str());
  }
  if (!model.retraceShare)
    throw InvalidParameter("movie plan: no retraceShare estimate");
  for (std::size_t k = 0; k < s.size(); ++k)
    if (!std::isfinite(s[k]))
      throw InvalidParameter("movie plan: the parameter of frame " + std::to_string(k) +
                             " is not finite");
  const double direction = s.size() > 1 && s[1] < s[0] ? -1.0 : 1.0;
  for (std::size_t k = 1; k < s.size(); ++k)
    if (!(direction * (s[k] - s[k - 1]) > 0))
      throw InvalidParameter("movie plan: the frames' parameters must change strictly "
                             "monotonically, frames " +
                             std::to_string(k - 1) + " and " + std::to_string(k) + " do not");
}

/// The planning of one movie: the best plan of each segment between two keys, by bisection.
struct Planner
{
  const std::vector<double>& s;
  const std::vector<bool>& stored;
  const MovieCostModel& model;
  std::vector<FramePlan>& frames;

  bool isStored(int k) const { return !this->stored.empty() && this->stored[k]; }
  double keyRays(int k) const
  {
    return this->isStored(k) ? 0.0 : this->model.wholeRays(this->s[static_cast<std::size_t>(k)]);
  }

  /// The frames strictly between keys i and j, each the cheaper of interpolating and tracing;
  /// returns their cost and writes them.
  double withoutKeys(int i, int j)
  {
    double total = 0;
    for (int k = i + 1; k < j; ++k)
    {
      const double share = this->model.retraceShare(this->s[i], this->s[j], this->s[k]);
      const double rays = this->model.interpolatedRays(this->s[k], share);
      const double whole = this->model.wholeRays(this->s[k]);
      FramePlan f;
      if (rays < whole) // false for NaN: the pair cannot make the frame
      {
        f.method = FrameMethod::Interpolated;
        f.keyBefore = i;
        f.keyAfter = j;
        f.share = share;
        f.rays = rays;
      }
      else
      {
        f.method = FrameMethod::Traced;
        f.share = 1;
        f.rays = whole;
      }
      this->frames[static_cast<std::size_t>(k)] = f;
      total += f.rays;
    }
    return total;
  }

  /// The cheapest plan of the frames strictly between keys i and j, written; returns its cost.
  double segment(int i, int j)
  {
    if (j - i < 2)
      return 0;
    // A stored frame in between is a key for free: split there first.
    for (int k = i + 1; k < j; ++k)
      if (this->isStored(k))
      {
        this->frames[static_cast<std::size_t>(k)] = reused();
        return this->segment(i, k) + this->segment(k, j);
      }
    const double flat = this->withoutKeys(i, j);
    const std::vector<FramePlan> flatPlan(this->frames.begin() + i + 1, this->frames.begin() + j);
    if (j - i < 3)
      return flat;
    const int m = i + (j - i) / 2;
    FramePlan key;
    key.method = FrameMethod::Key;
    key.share = 1;
    key.rays = this->keyRays(m);
    this->frames[static_cast<std::size_t>(m)] = key;
    const double split = key.rays + this->segment(i, m) + this->segment(m, j);
    if (split < flat)
      return split;
    std::copy(flatPlan.begin(), flatPlan.end(), this->frames.begin() + i + 1);
    return flat;
  }

  static FramePlan reused()
  {
    FramePlan f;
    f.method = FrameMethod::Reused;
    return f;
  }
};
}

namespace
{
/// A plan with no frames yet, holding the model's costs it counts.
MoviePlan describedPlan(const MovieCostModel& model)
{
  MoviePlan plan;
  plan.frameRays = model.frameRays;
  plan.retraceRays = model.retraceRays;
  plan.interpolationRays = model.interpolationRays;
  return plan;
}

/// One bisection plan: keys at the ends, at the stored frames and where splitting pays.
MoviePlan planOnce(const std::vector<double>& s, const std::vector<bool>& stored,
                   const MovieCostModel& model)
{
  const int n = static_cast<int>(s.size());
  MoviePlan plan;
  plan.frames.assign(s.size(), FramePlan());
  Planner planner{ s, stored, model, plan.frames };
  for (int k : { 0, n - 1 })
  {
    FramePlan& f = plan.frames[static_cast<std::size_t>(k)];
    if (planner.isStored(k))
      f = Planner::reused();
    else
    {
      f.method = FrameMethod::Key;
      f.share = 1;
      f.rays = model.wholeRays(s[static_cast<std::size_t>(k)]);
    }
  }
  planner.segment(0, n - 1);
  return plan;
}
}

MoviePlan planMovie(const std::vector<double>& s, const std::vector<bool>& stored,
                    const MovieCostModel& model)
{
  checkInput(s, stored, model);
  const std::size_t n = s.size();
  // A frame traced whole is stored whole, and then is a key for free: planned again with it
  // stored, the movie must come out the same, or running it again would plan other keys and
  // interpolate other frames. So the frames to trace whole join the stored ones until the plan
  // adds none (they only grow: at most n rounds); `joined` keeps why each was traced.
  std::vector<bool> whole = stored.empty() ? std::vector<bool>(n, false) : stored;
  std::vector<FrameMethod> joined(n, FrameMethod::Reused);
  MoviePlan inner;
  for (;;)
  {
    inner = planOnce(s, whole, model);
    bool grew = false;
    for (std::size_t k = 0; k < n; ++k)
    {
      const FrameMethod m = inner.frames[k].method;
      if ((m == FrameMethod::Key || m == FrameMethod::Traced) && !whole[k])
      {
        whole[k] = true;
        joined[k] = m;
        grew = true;
      }
    }
    if (!grew)
      break;
  }
  MoviePlan plan = describedPlan(model);
  plan.frames = inner.frames;
  for (std::size_t k = 0; k < n; ++k)
  {
    const bool wasStored = !stored.empty() && stored[k];
    FramePlan& f = plan.frames[k];
    const double wholeRays = model.wholeRays(s[k]);
    if (whole[k] && !wasStored)
    {
      f = FramePlan();
      f.method = joined[k];
      f.share = 1;
      f.rays = wholeRays;
    }
    plan.estimatedRays += f.rays;
    plan.tracedAllRays += wholeRays;
    plan.directRays += wasStored ? 0.0 : wholeRays;
  }
  return plan;
}

std::optional<MoviePlan> planBetweenStored(const std::vector<double>& s,
                                           const std::vector<bool>& stored,
                                           const std::vector<bool>& served,
                                           const MovieCostModel& model)
{
  checkInput(s, stored, model);
  if (!served.empty() && served.size() != s.size())
    throw InvalidParameter("movie plan: " + std::to_string(served.size()) + " served flags for " +
                           std::to_string(s.size()) + " frames");
  const std::size_t n = s.size();
  if (stored.empty() || !stored.front() || !stored.back())
    return std::nullopt;
  MoviePlan plan = describedPlan(model);
  plan.frames.assign(n, FramePlan());
  std::size_t before = 0;
  for (std::size_t k = 0; k < n; ++k)
  {
    FramePlan& f = plan.frames[k];
    const double wholeRays = model.wholeRays(s[k]);
    plan.tracedAllRays += wholeRays;
    if (stored[k])
    {
      f.method = FrameMethod::Reused;
      before = k;
      continue;
    }
    plan.directRays += wholeRays;
    std::size_t after = k + 1;
    while (!stored[after])
      ++after;
    const double share = model.retraceShare(s[before], s[after], s[k]);
    const bool isServed = !served.empty() && served[k];
    const double rays = model.interpolatedRays(s[k], share);
    if (!isServed && !(rays < wholeRays))
      return std::nullopt;
    f.method = FrameMethod::Interpolated;
    f.keyBefore = static_cast<int>(before);
    f.keyAfter = static_cast<int>(after);
    f.share = share;
    f.rays = isServed ? 0.0 : rays;
    plan.estimatedRays += f.rays;
  }
  return plan;
}

double SpacingShareModel::share(double keyA, double keyB) const
{
  const double length = this->pathLength > 0 ? this->pathLength : 1.0;
  const double spacing = std::abs(keyB - keyA) / length;
  // The narrowest measured pair around the keys stands for their stretch of the path.
  const double lo = std::min(keyA, keyB), hi = std::max(keyA, keyB);
  const double slack = 1e-9 * length;
  double slope = this->slope, narrowest = std::numeric_limits<double>::infinity();
  for (const Measurement& m : this->measurements)
  {
    const double mLo = std::min(m.keyA, m.keyB), mHi = std::max(m.keyA, m.keyB);
    if (mLo <= lo + slack && hi <= mHi + slack && mHi - mLo < narrowest)
    {
      narrowest = mHi - mLo;
      // A saturated measurement only bounds the slope from below.
      slope = m.saturated ? std::max(m.slope, this->slope) : m.slope;
    }
  }
  return std::min(1.0, this->floor + slope * spacing);
}

void SpacingShareModel::observe(double keyA, double keyB, double measuredShare)
{
  const double spacing = std::abs(keyB - keyA) / (this->pathLength > 0 ? this->pathLength : 1.0);
  if (!(spacing > 0) || !std::isfinite(measuredShare))
    return;
  const double measuredSlope = std::max(0.0, measuredShare - this->floor) / spacing;
  // A pair that re-traced everything says only that the slope is at least this: it raises the
  // prior while nothing else is measured, and the mean is of the other measurements.
  const bool saturated = measuredShare >= 1;
  if (saturated)
  {
    if (this->measured == 0)
      this->slope = std::max(this->slope, measuredSlope);
  }
  else
  {
    this->measuredSlopeSum += measuredSlope;
    ++this->measured;
    this->slope = this->measuredSlopeSum / this->measured;
  }
  this->measurements.push_back({ keyA, keyB, measuredSlope, saturated });
}

RetraceShare SpacingShareModel::function() const
{
  const SpacingShareModel copy = *this;
  return [copy](double keyA, double keyB, double) { return copy.share(keyA, keyB); };
}

namespace
{
/// The plan's next whole frame to make, coarse first: a missing end, else the frame nearest the
/// middle of the widest gap between whole frames that holds one; -1 when every one is whole.
int nextWhole(const MoviePlan& plan, const std::vector<double>& s, const std::vector<bool>& whole)
{
  const int n = static_cast<int>(s.size());
  for (int end : { 0, n - 1 })
    if (!whole[static_cast<std::size_t>(end)])
      return end;
  int best = -1;
  double widest = -1, offCentre = 0;
  int before = 0;
  for (int k = 1; k < n; ++k)
  {
    if (whole[static_cast<std::size_t>(k)])
    {
      before = k;
      continue;
    }
    if (plan.frames[static_cast<std::size_t>(k)].method == FrameMethod::Interpolated)
      continue;
    int after = k + 1;
    while (!whole[static_cast<std::size_t>(after)])
      ++after;
    const double gap =
      std::abs(s[static_cast<std::size_t>(after)] - s[static_cast<std::size_t>(before)]);
    const double centre =
      std::abs(s[static_cast<std::size_t>(k)] -
               0.5 * (s[static_cast<std::size_t>(after)] + s[static_cast<std::size_t>(before)]));
    if (gap > widest || (gap == widest && centre < offCentre))
    {
      best = k;
      widest = gap;
      offCentre = centre;
    }
  }
  return best;
}
}

namespace
{
/// Where s lies among points sorted by s: the points before and after it and the weight of the
/// one after (linear in s), the nearest one's alone beyond them. Points must not be empty.
template<typename Point>
void bracket(const std::vector<Point>& points, double s, std::size_t& before, std::size_t& after,
             double& w)
{
  const auto next = std::upper_bound(points.begin(), points.end(), s,
                                     [](double v, const Point& p) { return v < p.s; });
  after = static_cast<std::size_t>(std::min(next, points.end() - 1) - points.begin());
  before = next == points.begin() ? 0 : static_cast<std::size_t>(next - points.begin()) - 1;
  w = after == before ? 0.0 : (s - points[before].s) / (points[after].s - points[before].s);
}

/// Inserts p among points sorted by s, after those at the same s.
template<typename Point>
void insertByS(std::vector<Point>& points, const Point& p)
{
  points.insert(std::upper_bound(points.begin(), points.end(), p.s,
                                 [](double v, const Point& q) { return v < q.s; }),
                p);
}

/// The rays of the whole frames made, along the path.
struct WholeAlongPath
{
  struct Point
  {
    double s = 0, rays = 0;
  };
  std::vector<Point> points; ///< sorted by s
  double fallback = 0;

  void add(const Point& p) { insertByS(this->points, p); }
  double at(double s) const
  {
    if (this->points.empty())
      return this->fallback;
    std::size_t a = 0, b = 0;
    double w = 0;
    bracket(this->points, s, a, b, w);
    return (1 - w) * this->points[a].rays + w * this->points[b].rays;
  }
};

/// The re-traces measured, along the path: each scaled to the share asked for, then linear in s
/// between the measured frames around s.
struct RetraceAlongPath
{
  struct Point
  {
    double s = 0;
    ShareMeasurement m;
  };
  std::vector<Point> points; ///< sorted by s
  double pixels = 0;
  double fallbackEdgeRays = 0;

  void add(const Point& p) { insertByS(this->points, p); }
  /// The measured re-trace at another share: its pixels' own rays in proportion, their edge
  /// neighbours as the perimeter of patches that grow (√ of the share), the edges' midpoints and
  /// samples as they are.
  double scaled(const ShareMeasurement& m, double share) const
  {
    const double neighbours = m.share > 0 ? m.neighbourRays * std::sqrt(share / m.share) : 0.0;
    return share * this->pixels * m.raysPerPixel + neighbours + m.edgeRays;
  }
  double at(double s, double share) const
  {
    if (this->points.empty())
      return share * this->pixels + this->fallbackEdgeRays;
    std::size_t a = 0, b = 0;
    double w = 0;
    bracket(this->points, s, a, b, w);
    return (1 - w) * this->scaled(this->points[a].m, share) +
           w * this->scaled(this->points[b].m, share);
  }
};
}

MoviePlan planProgressively(const std::vector<double>& s, const std::vector<bool>& stored,
                            double pixels, SpacingShareModel& share, const KeyMaking& making,
                            const MovieCostPrior& prior)
{
  if (!(pixels > 0 && std::isfinite(pixels)))
    throw InvalidParameter("movie plan: pixels must be positive and finite");
  if (!making.makeWhole || !making.measureShare)
    throw InvalidParameter("movie plan: no way to make or measure frames");
  const std::size_t n = s.size();
  std::vector<bool> whole = stored.empty() ? std::vector<bool>(n, false) : stored;
  std::vector<FrameMethod> madeAs(n, FrameMethod::Reused);
  std::vector<double> madeRays(n, 0.0);
  double keyRays = 0, keys = 0, retracedPixels = 0, retracedRays = 0;
  MovieCostModel model = prior.model(pixels, share.function());
  WholeAlongPath wholeAlong;
  wholeAlong.fallback = model.frameRays;
  RetraceAlongPath retraceAlong;
  retraceAlong.pixels = pixels;
  retraceAlong.fallbackEdgeRays = pixels * prior.edgeRaysPerPixel;
  auto updateModel = [&]()
  {
    model.frameRays = keys > 0 && keyRays > 0 ? keyRays / keys : pixels * prior.wholeRaysPerPixel;
    model.wholeRaysAt = [wholeAlong](double at) { return wholeAlong.at(at); };
    model.retraceRays = retracedPixels > 0 ? pixels * retracedRays / retracedPixels : pixels;
    model.retraceRaysAt = [retraceAlong](double at, double part)
    { return retraceAlong.at(at, part); };
    model.retraceShare = share.function();
  };
  auto measure = [&](int k)
  {
    int before = k - 1, after = k + 1;
    while (before >= 0 && !whole[static_cast<std::size_t>(before)])
      --before;
    while (after < static_cast<int>(n) && !whole[static_cast<std::size_t>(after)])
      ++after;
    if (before < 0 || after >= static_cast<int>(n))
      return;
    const ShareMeasurement m = making.measureShare(k, before, after);
    share.observe(s[static_cast<std::size_t>(before)], s[static_cast<std::size_t>(after)], m.share);
    if (m.share > 0 && m.raysPerPixel > 0 && std::isfinite(m.raysPerPixel))
    {
      retracedPixels += m.share * pixels;
      retracedRays += m.share * pixels * m.raysPerPixel;
    }
    if (m.share >= 0 && m.share <= 1 && m.raysPerPixel >= 0 && std::isfinite(m.raysPerPixel) &&
        m.neighbourRays >= 0 && std::isfinite(m.neighbourRays) && m.edgeRays >= 0 &&
        std::isfinite(m.edgeRays))
      retraceAlong.add({ s[static_cast<std::size_t>(k)], m });
  };
  // What earlier runs stored is measured first, each stored frame between the stored frames
  // around it, for no ray: the prior of this run.
  for (std::size_t k = 0; k < n; ++k)
    if (whole[k])
      measure(static_cast<int>(k));
  updateModel();
  for (;;)
  {
    const MoviePlan plan = planMovie(s, whole, model);
    const int k = nextWhole(plan, s, whole);
    if (k < 0)
      break;
    const auto at = static_cast<std::size_t>(k);
    madeAs[at] = plan.frames[at].method;
    madeRays[at] = making.makeWhole(k);
    whole[at] = true;
    keyRays += madeRays[at];
    ++keys;
    if (madeRays[at] > 0 && std::isfinite(madeRays[at]))
      wholeAlong.add({ s[at], madeRays[at] });
    // A frame traced because interpolating it costs more is not measured: measuring interpolates
    // it, which would cost what tracing it saved.
    if (madeAs[at] != FrameMethod::Traced)
      measure(k);
    updateModel();
  }
  MoviePlan plan = planMovie(s, whole, model);
  plan.estimatedRays = plan.directRays = 0;
  for (std::size_t k = 0; k < n; ++k)
  {
    FramePlan& f = plan.frames[k];
    const bool wasStored = !stored.empty() && stored[k];
    if (f.method == FrameMethod::Reused && !wasStored)
    {
      f.method = madeAs[k] == FrameMethod::Traced ? FrameMethod::Traced : FrameMethod::Key;
      f.share = 1;
      f.rays = madeRays[k];
    }
    plan.estimatedRays += f.rays;
    plan.directRays += wasStored ? 0.0 : model.wholeRays(s[k]);
  }
  return plan;
}

std::vector<int> keysAround(const std::vector<int>& keys, int k)
{
  const auto after = std::upper_bound(keys.begin(), keys.end(), k);
  const std::ptrdiff_t before = after - keys.begin(), rest = keys.end() - after;
  // Two on either side; a side short of two lends its places to the other.
  const std::ptrdiff_t right =
    std::min<std::ptrdiff_t>(rest, 4 - std::min<std::ptrdiff_t>(2, before));
  const std::ptrdiff_t left = std::min<std::ptrdiff_t>(before, 4 - right);
  return std::vector<int>(after - left, after + right);
}

}
