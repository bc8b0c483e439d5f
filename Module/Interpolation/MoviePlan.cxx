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

double MovieCostModel::interpolatedRays(double share) const
{
  if (!(share >= 0 && share < 1))
    return std::numeric_limits<double>::quiet_NaN();
  return share * (this->retraceRays > 0 ? this->retraceRays : this->frameRays);
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
  double keyRays(int k) const { return this->isStored(k) ? 0.0 : this->model.frameRays; }

  /// The frames strictly between keys i and j, each the cheaper of interpolating and tracing;
  /// returns their cost and writes them.
  double withoutKeys(int i, int j)
  {
    double total = 0;
    for (int k = i + 1; k < j; ++k)
    {
      const double share = this->model.retraceShare(this->s[i], this->s[j], this->s[k]);
      const double rays = this->model.interpolatedRays(share);
      FramePlan f;
      if (rays < this->model.frameRays) // false for NaN: the pair cannot make the frame
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
        f.rays = this->model.frameRays;
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
      f.rays = model.frameRays;
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
  MoviePlan plan;
  plan.frames = inner.frames;
  plan.frameRays = model.frameRays;
  plan.retraceRays = model.retraceRays;
  for (std::size_t k = 0; k < n; ++k)
  {
    const bool wasStored = !stored.empty() && stored[k];
    FramePlan& f = plan.frames[k];
    if (whole[k] && !wasStored)
    {
      f = FramePlan();
      f.method = joined[k];
      f.share = 1;
      f.rays = model.frameRays;
    }
    plan.estimatedRays += f.rays;
    plan.tracedAllRays += model.frameRays;
    plan.directRays += wasStored ? 0.0 : model.frameRays;
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
  MoviePlan plan;
  plan.frames.assign(n, FramePlan());
  plan.frameRays = model.frameRays;
  plan.retraceRays = model.retraceRays;
  std::size_t before = 0;
  for (std::size_t k = 0; k < n; ++k)
  {
    FramePlan& f = plan.frames[k];
    plan.tracedAllRays += model.frameRays;
    if (stored[k])
    {
      f.method = FrameMethod::Reused;
      before = k;
      continue;
    }
    plan.directRays += model.frameRays;
    std::size_t after = k + 1;
    while (!stored[after])
      ++after;
    const double share = model.retraceShare(s[before], s[after], s[k]);
    const bool isServed = !served.empty() && served[k];
    const double rays = model.interpolatedRays(share);
    if (!isServed && !(rays < model.frameRays))
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

MoviePlan planProgressively(const std::vector<double>& s, const std::vector<bool>& stored,
                            double pixels, SpacingShareModel& share, const KeyMaking& making)
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
  MovieCostModel model;
  auto updateModel = [&]()
  {
    model.frameRays = keys > 0 && keyRays > 0 ? keyRays / keys : pixels;
    model.retraceRays = retracedPixels > 0 ? pixels * retracedRays / retracedPixels : 0.0;
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
    plan.directRays += wasStored ? 0.0 : model.frameRays;
  }
  return plan;
}
}
