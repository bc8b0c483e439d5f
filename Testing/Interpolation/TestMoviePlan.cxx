// The movie planner on synthetic costs: what it chooses is checked against the cost model
// evaluated again here, and against the cheapest plan found by trying every set of keys.
#include "MoviePlan.h"

#include "AsrtTypes.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <optional>
#include <tuple>
#include <vector>

namespace
{
using asrt::FrameMethod;
using asrt::keysAround;

std::vector<double> evenPath(int n, double from = 0.0, double to = 1.0)
{
  std::vector<double> s;
  for (int k = 0; k < n; ++k)
    s.push_back(from + (to - from) * k / (n - 1));
  return s;
}

/// The plan's cost, evaluated again from its methods and keys with the model, and its
/// consistency: every interpolated frame lies between its keys, with no key between them.
double recomputedCost(const asrt::MoviePlan& plan, const std::vector<double>& s,
                      const asrt::MovieCostModel& model)
{
  double total = 0;
  for (std::size_t k = 0; k < plan.frames.size(); ++k)
  {
    const asrt::FramePlan& f = plan.frames[k];
    switch (f.method)
    {
      case FrameMethod::Reused:
        break;
      case FrameMethod::Key:
      case FrameMethod::Traced:
        total += model.wholeRays(s[k]);
        break;
      case FrameMethod::Interpolated:
      {
        EXPECT_LT(f.keyBefore, static_cast<int>(k));
        EXPECT_GT(f.keyAfter, static_cast<int>(k));
        for (int between = f.keyBefore + 1; between < f.keyAfter; ++between)
        {
          const FrameMethod m = plan.frames[static_cast<std::size_t>(between)].method;
          EXPECT_EQ(m, FrameMethod::Interpolated)
            << "frame " << between << " is a key between the keys of frame " << k;
        }
        const double share = model.retraceShare(s[static_cast<std::size_t>(f.keyBefore)],
                                                s[static_cast<std::size_t>(f.keyAfter)], s[k]);
        EXPECT_LT(share, 1.0) << "frame " << k << " interpolated where the pair cannot";
        total += model.interpolatedRays(s[k], share);
        break;
      }
    }
  }
  return total;
}

/// The cheapest cost over every set of keys (ends and stored frames always keys), each other
/// frame the cheaper of interpolating and tracing: the brute-force optimum for small movies.
double bruteForceOptimum(const std::vector<double>& s, const std::vector<bool>& stored,
                         const asrt::MovieCostModel& model)
{
  const int n = static_cast<int>(s.size());
  double best = std::numeric_limits<double>::infinity();
  for (std::uint32_t mask = 0; mask < (1u << (n - 2)); ++mask)
  {
    std::vector<bool> key(s.size(), false);
    key[0] = key[s.size() - 1] = true;
    for (int k = 1; k < n - 1; ++k)
      key[static_cast<std::size_t>(k)] =
        ((mask >> (k - 1)) & 1u) != 0 || stored[static_cast<std::size_t>(k)];
    double cost = 0;
    int before = 0;
    for (int k = 0; k < n; ++k)
    {
      if (key[static_cast<std::size_t>(k)])
      {
        cost += stored[static_cast<std::size_t>(k)] ? 0.0 : model.wholeRays(s[k]);
        before = k;
        continue;
      }
      int after = k + 1;
      while (!key[static_cast<std::size_t>(after)])
        ++after;
      const double share =
        model.retraceShare(s[static_cast<std::size_t>(before)], s[static_cast<std::size_t>(after)],
                           s[static_cast<std::size_t>(k)]);
      const double whole = model.wholeRays(s[static_cast<std::size_t>(k)]);
      cost += share >= 0 && share < 1
                ? std::min(whole, model.interpolatedRays(s[static_cast<std::size_t>(k)], share))
                : whole;
    }
    best = std::min(best, cost);
  }
  return best;
}

TEST(MoviePlan, TracesDirectlyWhenInterpolationCostsMore)
{
  const std::vector<double> s = evenPath(12);
  asrt::MovieCostModel model;
  model.frameRays = 1000;
  model.retraceShare = [](double, double, double) { return 1.2; }; // worse than tracing
  const asrt::MoviePlan plan = asrt::planMovie(s, {}, model);
  ASSERT_EQ(plan.frames.size(), s.size());
  for (std::size_t k = 1; k + 1 < s.size(); ++k)
    EXPECT_EQ(plan.frames[k].method, FrameMethod::Traced) << "frame " << k;
  EXPECT_EQ(plan.frames.front().method, FrameMethod::Key);
  EXPECT_EQ(plan.frames.back().method, FrameMethod::Key);
  EXPECT_DOUBLE_EQ(plan.estimatedRays, 12 * 1000.0);
  EXPECT_DOUBLE_EQ(plan.directRays, 12 * 1000.0);
}

TEST(MoviePlan, InterpolatesWhenCheapAndAddsNoKeyItDoesNotNeed)
{
  const std::vector<double> s = evenPath(10);
  asrt::MovieCostModel model;
  model.frameRays = 1000;
  model.retraceShare = [](double, double, double) { return 0.05; };
  const asrt::MoviePlan plan = asrt::planMovie(s, {}, model);
  EXPECT_EQ(plan.keys(), (std::vector<int>{ 0, 9 }));
  EXPECT_NEAR(plan.estimatedRays, 2000 + 8 * 50.0, 1e-9);
  EXPECT_NEAR(plan.estimatedRays, recomputedCost(plan, s, model), 1e-9);
}

TEST(MoviePlan, AddsAKeyWhereAPairCannotMeetTheTarget)
{
  // Interpolation meets the target only between keys at most 0.25 apart.
  const std::vector<double> s = evenPath(17);
  asrt::MovieCostModel model;
  model.frameRays = 1000;
  model.retraceShare = [](double a, double b, double)
  { return std::abs(b - a) <= 0.25 + 1e-12 ? 0.1 : std::numeric_limits<double>::infinity(); };
  const asrt::MoviePlan plan = asrt::planMovie(s, {}, model);
  const std::vector<int> keys = plan.keys();
  EXPECT_GT(keys.size(), 2u) << "no key was added between the ends";
  for (std::size_t k = 1; k < keys.size(); ++k)
    EXPECT_LE(s[static_cast<std::size_t>(keys[k])] - s[static_cast<std::size_t>(keys[k - 1])],
              0.25 + 1e-12);
  for (const asrt::FramePlan& f : plan.frames)
    EXPECT_NE(f.method, FrameMethod::Traced);
  EXPECT_NEAR(plan.estimatedRays, recomputedCost(plan, s, model), 1e-9);
  EXPECT_LT(plan.estimatedRays, 0.5 * plan.directRays);
}

TEST(MoviePlan, AddsAKeyOnlyWhereThePathIsHard)
{
  // Frames near s = 0.8 can only be interpolated between keys at most half the path apart;
  // elsewhere any pair does it cheaply. One key at the middle makes every frame interpolable.
  const std::vector<double> s = evenPath(21);
  asrt::MovieCostModel model;
  model.frameRays = 1000;
  model.retraceShare = [](double a, double b, double t)
  { return std::abs(t - 0.8) < 0.06 && std::abs(b - a) > 0.5 + 1e-12 ? 2.0 : 0.02; };
  const asrt::MoviePlan plan = asrt::planMovie(s, {}, model);
  EXPECT_EQ(plan.keys(), (std::vector<int>{ 0, 10, 20 }));
  for (std::size_t k = 0; k < s.size(); ++k)
  {
    if (k % 10 != 0)
    {
      EXPECT_EQ(plan.frames[k].method, FrameMethod::Interpolated) << "frame " << k;
    }
  }
  EXPECT_NEAR(plan.estimatedRays, recomputedCost(plan, s, model), 1e-9);
  EXPECT_NEAR(plan.estimatedRays, bruteForceOptimum(s, std::vector<bool>(s.size()), model), 1e-9);
}

TEST(MoviePlan, StoredFramesCostNothingAndAreKeys)
{
  const std::vector<double> s = evenPath(11);
  std::vector<bool> stored(s.size(), false);
  stored[0] = stored[5] = stored[10] = true;
  asrt::MovieCostModel model;
  model.frameRays = 1000;
  model.retraceShare = [](double, double, double) { return 1.5; };
  const asrt::MoviePlan plan = asrt::planMovie(s, stored, model);
  for (int k : { 0, 5, 10 })
  {
    EXPECT_EQ(plan.frames[static_cast<std::size_t>(k)].method, FrameMethod::Reused);
    EXPECT_EQ(plan.frames[static_cast<std::size_t>(k)].rays, 0.0);
  }
  EXPECT_DOUBLE_EQ(plan.estimatedRays, 8 * 1000.0);
  EXPECT_DOUBLE_EQ(plan.directRays, 8 * 1000.0);
  EXPECT_DOUBLE_EQ(plan.tracedAllRays, 11 * 1000.0);

  std::vector<bool> all(s.size(), true);
  EXPECT_DOUBLE_EQ(asrt::planMovie(s, all, model).estimatedRays, 0.0);
}

TEST(MoviePlan, BetweenStoredKeepsTheStoredKeysAndCountsServedFramesFree)
{
  // The 7-frame movie planned with keys 0, 3, 6, stored; the same path with 13 frames has them at
  // 0, 6, 12, and its even frames are the old interpolated ones, served by the store.
  const std::vector<double> s = evenPath(13);
  std::vector<bool> stored(s.size(), false), served(s.size(), false);
  stored[0] = stored[6] = stored[12] = true;
  for (int k : { 2, 4, 8, 10 })
    served[static_cast<std::size_t>(k)] = true;
  asrt::MovieCostModel model;
  model.frameRays = 1000;
  model.retraceShare = [](double a, double b, double) { return 0.01 + std::abs(b - a); };
  const std::optional<asrt::MoviePlan> plan = asrt::planBetweenStored(s, stored, served, model);
  ASSERT_TRUE(plan.has_value());
  EXPECT_EQ(plan->keys(), (std::vector<int>{ 0, 6, 12 }));
  for (int k = 1; k < 12; ++k)
  {
    const asrt::FramePlan& f = plan->frames[static_cast<std::size_t>(k)];
    if (k == 6)
      continue;
    EXPECT_EQ(f.method, FrameMethod::Interpolated) << k;
    EXPECT_EQ(f.keyBefore, k < 6 ? 0 : 6) << k;
    EXPECT_EQ(f.keyAfter, k < 6 ? 6 : 12) << k;
    EXPECT_DOUBLE_EQ(f.rays, served[static_cast<std::size_t>(k)] ? 0.0 : 510.0) << k;
  }
  // The six new frames at their share, nothing for the served ones.
  EXPECT_DOUBLE_EQ(plan->estimatedRays, 6 * 510.0);
  EXPECT_DOUBLE_EQ(plan->directRays, 10 * 1000.0);
  // The bisection, which knows nothing of what is served, adds keys to this denser movie and so
  // costs more by the same model once the served frames are counted.
  const asrt::MoviePlan bisected = asrt::planMovie(s, stored, model);
  EXPECT_GT(bisected.keys().size(), 3u);
  EXPECT_LT(plan->estimatedRays, bisected.estimatedRays);

  // No candidate when an end is not stored, or a frame cannot be interpolated between its keys.
  std::vector<bool> noEnd = stored;
  noEnd[12] = false;
  EXPECT_FALSE(asrt::planBetweenStored(s, noEnd, served, model).has_value());
  asrt::MovieCostModel hard = model;
  hard.retraceShare = [](double a, double b, double) { return std::abs(b - a) > 0.6 ? 1.0 : 0.2; };
  std::vector<bool> wide(s.size(), false);
  wide[0] = wide[12] = true;
  EXPECT_FALSE(asrt::planBetweenStored(s, wide, {}, hard).has_value());
  EXPECT_THROW(asrt::planBetweenStored(s, stored, std::vector<bool>(3, false), model),
               asrt::InvalidParameter);
}

TEST(MoviePlan, NeverCostsMoreThanTracingEveryFrameAndComesNearTheOptimum)
{
  // Pseudo-random share functions of the pair and the frame, with random stored frames.
  std::uint64_t state = 0x2545f4914f6cdd1dULL;
  auto next = [&state]()
  {
    state ^= state << 13;
    state ^= state >> 7;
    state ^= state << 17;
    return static_cast<double>(state >> 11) / 9007199254740992.0;
  };
  for (int trial = 0; trial < 200; ++trial)
  {
    const int n = 2 + static_cast<int>(next() * 11);
    const std::vector<double> s = evenPath(n, next(), 2 + next());
    std::vector<bool> stored(s.size());
    for (std::size_t k = 0; k < s.size(); ++k)
      stored[k] = next() < 0.15;
    const double steepness = 0.2 + 3 * next(), bump = next();
    asrt::MovieCostModel model;
    model.frameRays = 100 + 1000 * next();
    model.retraceShare = [steepness, bump](double a, double b, double t)
    { return steepness * std::abs(b - a) * (1 + std::sin(7 * t + bump)) / 2; };
    const asrt::MoviePlan plan = asrt::planMovie(s, stored, model);
    const double cost = recomputedCost(plan, s, model);
    EXPECT_NEAR(plan.estimatedRays, cost, 1e-6 * plan.directRays);
    EXPECT_LE(plan.estimatedRays, plan.directRays * (1 + 1e-12)) << "trial " << trial;
    const double optimum = bruteForceOptimum(s, stored, model);
    EXPECT_GE(plan.estimatedRays, optimum - 1e-6 * model.frameRays) << "trial " << trial;
    for (std::size_t k = 0; k < s.size(); ++k)
    {
      if (stored[k])
      {
        EXPECT_EQ(plan.frames[k].method, FrameMethod::Reused);
      }
    }
    // Run again with every frame it traces whole stored: the same keys, the same interpolations.
    std::vector<bool> after = stored;
    for (int k : plan.keys())
      after[static_cast<std::size_t>(k)] = true;
    const asrt::MoviePlan again = asrt::planMovie(s, after, model);
    EXPECT_EQ(again.keys(), plan.keys()) << "trial " << trial;
    for (std::size_t k = 0; k < s.size(); ++k)
    {
      EXPECT_EQ(again.frames[k].method == FrameMethod::Reused, after[k]);
      if (plan.frames[k].method == FrameMethod::Interpolated)
      {
        EXPECT_EQ(again.frames[k].method, FrameMethod::Interpolated);
        EXPECT_EQ(again.frames[k].keyBefore, plan.frames[k].keyBefore);
        EXPECT_EQ(again.frames[k].keyAfter, plan.frames[k].keyAfter);
      }
    }
    double interpolatedRays = 0;
    for (const asrt::FramePlan& f : again.frames)
      interpolatedRays += f.method == FrameMethod::Interpolated ? f.rays : 0;
    EXPECT_DOUBLE_EQ(again.estimatedRays, interpolatedRays) << "trial " << trial;
  }
}

TEST(MoviePlan, TracesWhereTheReTraceCostsMoreRaysThanTheFrame)
{
  // Each frame re-traces 30 % of its pixels, one ray each, on top of the rays its edges take
  // whatever the share (RetraceRays.h): below a whole frame's rays it is interpolated, above them
  // traced, interpolating it counted in.
  const std::vector<double> s = evenPath(9);
  auto modelOf = [](double edgeRays, double interpolationRays)
  {
    asrt::MovieCostModel model;
    model.frameRays = 1000;
    model.retraceRays = 1000;
    model.retraceRaysAt = [edgeRays](double, double share) { return 1000 * share + edgeRays; };
    model.interpolationRays = interpolationRays;
    model.retraceShare = [](double, double, double) { return 0.3; };
    return model;
  };
  for (const auto& [edge, interpolation, traced] :
       { std::tuple(500.0, 0.0, false), std::tuple(750.0, 0.0, true),
         std::tuple(500.0, 150.0, false), std::tuple(600.0, 150.0, true) })
  {
    const asrt::MovieCostModel model = modelOf(edge, interpolation);
    const asrt::MoviePlan plan = asrt::planMovie(s, {}, model);
    const double interpolated = 300 + edge + interpolation;
    for (std::size_t k = 1; k + 1 < s.size(); ++k)
      EXPECT_EQ(plan.frames[k].method, traced ? FrameMethod::Traced : FrameMethod::Interpolated)
        << "frame " << k << ", edges " << edge << ", interpolating " << interpolation;
    EXPECT_NEAR(plan.estimatedRays, 2000 + 7 * std::min(1000.0, interpolated), 1e-9);
    EXPECT_NEAR(plan.estimatedRays, recomputedCost(plan, s, model), 1e-9);
    EXPECT_LE(plan.estimatedRays, plan.directRays);
  }
  asrt::MovieCostModel bad = modelOf(0, -1);
  EXPECT_THROW(asrt::planMovie(s, {}, bad), asrt::InvalidParameter);
}

TEST(MoviePlan, EachFrameIsWeighedAgainstItsOwnWholeRays)
{
  // Whole frames take 400 rays at the start of the path and 1600 at its end; interpolating any
  // frame takes 1000. Frames are traced where that is cheaper, interpolated elsewhere, and tracing
  // every frame costs the sum of their own rays.
  const std::vector<double> s = evenPath(13);
  asrt::MovieCostModel model;
  model.frameRays = 1000;
  model.wholeRaysAt = [](double at) { return 400 + 1200 * at; };
  model.retraceRaysAt = [](double, double) { return 1000.0; };
  model.retraceShare = [](double, double, double) { return 0.1; };
  const asrt::MoviePlan plan = asrt::planMovie(s, {}, model);
  double direct = 0;
  for (std::size_t k = 0; k < s.size(); ++k)
  {
    direct += model.wholeRays(s[k]);
    if (plan.frames[k].method == FrameMethod::Interpolated)
    {
      EXPECT_GT(model.wholeRays(s[k]), 1000.0) << "frame " << k;
    }
    else
    {
      if (k > 0 && k + 1 < s.size()) // the ends are keys whatever they cost
      {
        EXPECT_LE(model.wholeRays(s[k]), 1000.0 + 1e-9) << "frame " << k;
      }
      EXPECT_DOUBLE_EQ(plan.frames[k].rays, model.wholeRays(s[k])) << "frame " << k;
    }
  }
  EXPECT_EQ(plan.frames[2].method, FrameMethod::Traced);
  EXPECT_EQ(plan.frames[10].method, FrameMethod::Interpolated);
  EXPECT_DOUBLE_EQ(plan.directRays, direct);
  EXPECT_NEAR(plan.estimatedRays, recomputedCost(plan, s, model), 1e-9);
  EXPECT_NEAR(plan.estimatedRays, bruteForceOptimum(s, std::vector<bool>(s.size()), model), 1e-9);
}

TEST(MoviePlan, ThePriorCountsTheEdgesAndTheInterpolation)
{
  asrt::MovieCostPrior prior;
  prior.wholeRaysPerPixel = 1.1;
  prior.edgeRaysPerPixel = 0.6;
  prior.interpolationRaysPerPixel = 0.15;
  const asrt::MovieCostModel model = prior.model(1000, [](double, double, double) { return 0.2; });
  EXPECT_DOUBLE_EQ(model.wholeRays(0.3), 1100);
  EXPECT_DOUBLE_EQ(model.interpolatedRays(0.3, 0.2), 200 + 600 + 150);
  EXPECT_TRUE(std::isnan(model.interpolatedRays(0.3, 1.0)));
  // So with these priors a frame is interpolated only below a share of 0.35.
  const asrt::MoviePlan plan = asrt::planMovie(evenPath(5), {}, model);
  EXPECT_EQ(plan.frames[2].method, FrameMethod::Interpolated);
  asrt::MovieCostModel dear = model;
  dear.retraceShare = [](double, double, double) { return 0.36; };
  EXPECT_EQ(asrt::planMovie(evenPath(5), {}, dear).frames[2].method, FrameMethod::Traced);
}

// The keys a frame is interpolated from: the nearest 4, against every set of 4 consecutive keys
// around the frame (brute force): two on either side inside, the 4 at an end, all where fewer.
TEST(MoviePlan, FramesAreInterpolatedFromTheNearestFourKeys)
{
  const std::vector<int> keys = { 0, 3, 7, 8, 12, 20, 24 };
  for (int k = 1; k < 24; ++k)
  {
    if (std::binary_search(keys.begin(), keys.end(), k))
      continue;
    const std::vector<int> around = keysAround(keys, k);
    ASSERT_EQ(around.size(), 4u) << "frame " << k;
    EXPECT_TRUE(std::is_sorted(around.begin(), around.end()));
    EXPECT_LT(around[0], k);
    EXPECT_GT(around[3], k);
    // No other run of 4 consecutive keys bracketing k lies nearer: the farthest of its keys from
    // k in index steps is the least, and the inner pair is always in.
    const auto inner = std::upper_bound(keys.begin(), keys.end(), k) - keys.begin();
    EXPECT_TRUE(std::count(around.begin(), around.end(), keys[inner - 1]) == 1 &&
                std::count(around.begin(), around.end(), keys[inner]) == 1)
      << "frame " << k;
    const auto first = std::find(keys.begin(), keys.end(), around[0]) - keys.begin();
    std::ptrdiff_t bestReach = 100;
    for (std::ptrdiff_t f = 0; f + 4 <= static_cast<std::ptrdiff_t>(keys.size()); ++f)
      if (f < inner && f + 3 >= inner)
        bestReach = std::min(bestReach, std::max(inner - f, f + 4 - inner));
    EXPECT_EQ(std::max(inner - first, first + 4 - inner), bestReach) << "frame " << k;
  }
  EXPECT_EQ(keysAround(keys, 1), (std::vector<int>{ 0, 3, 7, 8 }));
  EXPECT_EQ(keysAround(keys, 10), (std::vector<int>{ 7, 8, 12, 20 }));
  EXPECT_EQ(keysAround(keys, 22), (std::vector<int>{ 8, 12, 20, 24 }));
  EXPECT_EQ(keysAround({ 0, 5, 9 }, 2), (std::vector<int>{ 0, 5, 9 }));
  EXPECT_EQ(keysAround({ 0, 9 }, 4), (std::vector<int>{ 0, 9 }));
}

TEST(MoviePlan, RefusesBadInputNamingIt)
{
  asrt::MovieCostModel model;
  model.frameRays = 1000;
  model.retraceShare = [](double, double, double) { return 0.1; };
  EXPECT_THROW(asrt::planMovie({}, {}, model), asrt::InvalidParameter);
  EXPECT_THROW(asrt::planMovie({ 0, 1, 1 }, {}, model), asrt::InvalidParameter);
  EXPECT_THROW(asrt::planMovie({ 0, 2, 1 }, {}, model), asrt::InvalidParameter);
  EXPECT_THROW(asrt::planMovie({ 0, std::nan(""), 1 }, {}, model), asrt::InvalidParameter);
  EXPECT_THROW(asrt::planMovie({ 0, 1 }, { true }, model), asrt::InvalidParameter);
  asrt::MovieCostModel none = model;
  none.retraceShare = nullptr;
  EXPECT_THROW(asrt::planMovie({ 0, 1 }, {}, none), asrt::InvalidParameter);
  none = model;
  none.frameRays = 0;
  EXPECT_THROW(asrt::planMovie({ 0, 1 }, {}, none), asrt::InvalidParameter);
  // Decreasing parameters are a path too.
  EXPECT_NO_THROW(asrt::planMovie({ 1, 0.5, 0 }, {}, model));
  EXPECT_EQ(asrt::planMovie({ 3.0 }, {}, model).frames.size(), 1u);
}

TEST(MoviePlan, SpacingModelLearnsTheMeasuredSlope)
{
  asrt::SpacingShareModel m;
  m.pathLength = 2;
  m.floor = 0.01;
  m.slope = 1;
  EXPECT_NEAR(m.share(0, 1), 0.51, 1e-12);
  m.observe(0, 0.5, 0.06); // (0.06 - 0.01) / 0.25
  EXPECT_NEAR(m.slope, 0.2, 1e-12);
  m.observe(0, 1, 0.31); // (0.31 - 0.01) / 0.5 = 0.6
  EXPECT_NEAR(m.slope, 0.4, 1e-12);
  EXPECT_NEAR(m.function()(0, 2, 1), 0.41, 1e-12);
  EXPECT_EQ(m.share(0, 100), 1.0);
}
}

namespace
{
/// A movie whose true re-trace share is known: floor + slope(pair) · spacing, and whose whole
/// frames take `keyRays` rays; planned progressively from a prior slope of 1, every frame made and
/// measured recorded.
struct SyntheticMovie
{
  std::vector<double> s = evenPath(31);
  double pixels = 1000, keyRays = 1000, floor = 0.01;
  double edgeRays = 0; ///< what every re-trace takes beyond its pixels' rays
  std::function<double(double a, double b)> slope;
  std::vector<int> made;
  int measured = 0;

  double trueShare(double a, double b) const
  {
    return std::min(1.0, this->floor + this->slope(a, b) * std::abs(b - a));
  }
  asrt::MovieCostModel trueModel() const
  {
    asrt::MovieCostModel model;
    model.frameRays = this->keyRays;
    model.retraceRays = this->pixels;
    model.retraceShare = [this](double a, double b, double) { return this->trueShare(a, b); };
    return model;
  }
  asrt::MoviePlan plan(asrt::SpacingShareModel& share)
  {
    share.pathLength = 1;
    share.floor = this->floor;
    share.slope = 1;
    asrt::KeyMaking making;
    making.makeWhole = [this](int k)
    {
      this->made.push_back(k);
      return this->keyRays;
    };
    making.measureShare = [this](int k, int before, int after)
    {
      EXPECT_LT(before, k);
      EXPECT_GT(after, k);
      for (int between = before + 1; between < after; ++between)
        EXPECT_EQ(std::count(this->made.begin(), this->made.end(), between), between == k ? 1 : 0)
          << "frame " << k << " measured between " << before << " and " << after;
      ++this->measured;
      asrt::ShareMeasurement m;
      m.share = this->trueShare(this->s[static_cast<std::size_t>(before)],
                                this->s[static_cast<std::size_t>(after)]);
      m.raysPerPixel = 1;
      m.edgeRays = this->edgeRays;
      return m;
    };
    return asrt::planProgressively(this->s, {}, this->pixels, share, making);
  }
};

/// The prior's plan: what a movie planned without measuring would use.
asrt::MoviePlan priorPlan(const SyntheticMovie& movie)
{
  asrt::SpacingShareModel prior;
  prior.floor = movie.floor;
  asrt::MovieCostModel model;
  model.frameRays = movie.pixels;
  model.retraceShare = prior.function();
  return asrt::planMovie(movie.s, {}, model);
}

/// A plan by the true costs: an interpolated frame re-traces its true share (all of it where the
/// pair cannot make it: a share learnt as a lower bound, or the prior, may send one there).
double trueCost(const SyntheticMovie& movie, const asrt::MoviePlan& plan)
{
  const asrt::MovieCostModel truth = movie.trueModel();
  double total = 0;
  for (std::size_t k = 0; k < plan.frames.size(); ++k)
  {
    const asrt::FramePlan& f = plan.frames[k];
    if (f.method == FrameMethod::Interpolated)
    {
      EXPECT_LT(f.keyBefore, static_cast<int>(k));
      EXPECT_GT(f.keyAfter, static_cast<int>(k));
      total +=
        truth.retraceRays * truth.retraceShare(movie.s[static_cast<std::size_t>(f.keyBefore)],
                                               movie.s[static_cast<std::size_t>(f.keyAfter)], 0);
    }
    else
      total += truth.frameRays;
  }
  return total;
}

/// Checks what holds for every progressive plan: each whole frame made once, and exactly the
/// plan's keys; every frame but the ends measured; its cost, by the true model, near the plan made
/// knowing the true model, and no more than tracing every frame.
void checkProgressive(const SyntheticMovie& movie, const asrt::MoviePlan& plan)
{
  std::vector<int> made = movie.made;
  std::sort(made.begin(), made.end());
  EXPECT_TRUE(std::adjacent_find(made.begin(), made.end()) == made.end()) << "a frame made twice";
  EXPECT_EQ(made, plan.keys());
  const asrt::MovieCostModel truth = movie.trueModel();
  // Near what the same bisection makes knowing the true costs from the start (only the keys made
  // before the first measurements are the prior's), and no dearer than tracing every frame.
  const double cost = trueCost(movie, plan),
               oracle = trueCost(movie, asrt::planMovie(movie.s, {}, truth));
  EXPECT_LE(cost, 1.05 * oracle);
  EXPECT_LE(cost, truth.frameRays * static_cast<double>(movie.s.size()));
  // Every key but the ends measured; frames traced because interpolating costs more are not.
  const auto keys =
    std::count_if(plan.frames.begin(), plan.frames.end(),
                  [](const asrt::FramePlan& f) { return f.method == FrameMethod::Key; });
  EXPECT_EQ(movie.measured, static_cast<int>(keys) - 2);
}
}

TEST(MoviePlanProgressive, FewerKeysWhenTheMeasuredShareIsLowMoreWhenHigh)
{
  const std::size_t priorKeys = priorPlan(SyntheticMovie()).keys().size();
  SyntheticMovie low, high;
  low.slope = [](double, double) { return 0.3; };
  high.slope = [](double, double) { return 6.0; };
  asrt::SpacingShareModel lowShare, highShare;
  const asrt::MoviePlan lowPlan = low.plan(lowShare), highPlan = high.plan(highShare);
  checkProgressive(low, lowPlan);
  checkProgressive(high, highPlan);
  EXPECT_LT(lowPlan.keys().size(), priorKeys);
  EXPECT_GT(highPlan.keys().size(), priorKeys);
  // And so each costs less, by the true costs, than the prior's plan.
  EXPECT_LT(trueCost(low, lowPlan), trueCost(low, priorPlan(low)));
  EXPECT_LT(trueCost(high, highPlan), trueCost(high, priorPlan(high)));
  // A linear share is measured exactly: the model ends with the true slope.
  EXPECT_NEAR(lowShare.slope, 0.3, 1e-9);
  EXPECT_NEAR(highShare.slope, 6.0, 1e-9);
  // Made coarse first: the ends, then the middle.
  ASSERT_GE(high.made.size(), 3u);
  EXPECT_EQ((std::vector<int>(high.made.begin(), high.made.begin() + 3)),
            (std::vector<int>{ 0, 30, 15 }));
}

TEST(MoviePlanProgressive, CostlierKeysMeanFewerKeys)
{
  // The same shares, whole frames taking twice the rays of re-tracing every pixel once: never
  // more keys, and fewer for some slopes (the bisection's key counts are coarse).
  bool fewer = false;
  for (double slope : { 0.5, 1.0, 2.0, 3.0, 4.0, 6.0, 8.0 })
  {
    SyntheticMovie cheap, costly;
    cheap.slope = costly.slope = [slope](double, double) { return slope; };
    costly.keyRays = 2 * costly.pixels;
    asrt::SpacingShareModel a, b;
    const asrt::MoviePlan cheapPlan = cheap.plan(a), costlyPlan = costly.plan(b);
    checkProgressive(cheap, cheapPlan);
    checkProgressive(costly, costlyPlan);
    EXPECT_LE(costlyPlan.keys().size(), cheapPlan.keys().size()) << "slope " << slope;
    fewer = fewer || costlyPlan.keys().size() < cheapPlan.keys().size();
    EXPECT_DOUBLE_EQ(costlyPlan.frameRays, 2 * costly.pixels);
  }
  EXPECT_TRUE(fewer);
}

TEST(MoviePlanProgressive, AMeasuredStretchKeepsItsOwnSlope)
{
  // Edges barely move on the first half of the path and fast on the second.
  SyntheticMovie movie;
  movie.slope = [](double a, double b) { return std::max(a, b) <= 0.5 ? 0.2 : 6.0; };
  asrt::SpacingShareModel share;
  const asrt::MoviePlan plan = movie.plan(share);
  checkProgressive(movie, plan);
  const std::vector<int> keys = plan.keys();
  const auto firstHalf = std::count_if(keys.begin(), keys.end(), [](int k) { return k < 15; });
  const auto secondHalf = std::count_if(keys.begin(), keys.end(), [](int k) { return k > 15; });
  EXPECT_LT(firstHalf + 2, secondHalf);
}

TEST(MoviePlanProgressive, StoredFramesAreKeysForFree)
{
  SyntheticMovie movie;
  movie.slope = [](double, double) { return 2.0; };
  std::vector<bool> stored(movie.s.size(), false);
  stored[0] = stored[10] = stored[30] = true;
  asrt::SpacingShareModel share;
  asrt::KeyMaking making;
  making.makeWhole = [&movie](int k)
  {
    movie.made.push_back(k);
    return movie.keyRays;
  };
  std::vector<std::array<int, 3>> measured;
  making.measureShare = [&movie, &measured](int k, int before, int after)
  {
    measured.push_back({ k, before, after });
    asrt::ShareMeasurement m;
    m.share = movie.trueShare(movie.s[static_cast<std::size_t>(before)],
                              movie.s[static_cast<std::size_t>(after)]);
    return m;
  };
  const asrt::MoviePlan plan =
    asrt::planProgressively(movie.s, stored, movie.pixels, share, making);
  for (int k : { 0, 10, 30 })
  {
    EXPECT_EQ(plan.frames[static_cast<std::size_t>(k)].method, FrameMethod::Reused);
    EXPECT_EQ(std::count(movie.made.begin(), movie.made.end(), k), 0);
  }
  EXPECT_DOUBLE_EQ(plan.directRays, 28 * movie.keyRays);
  // The stored frame between stored ones is measured first: the prior of this run, exact here.
  ASSERT_FALSE(measured.empty());
  EXPECT_EQ(measured.front(), (std::array<int, 3>{ 10, 0, 30 }));
  EXPECT_NEAR(share.slope, 2.0, 1e-9);
  asrt::KeyMaking none;
  EXPECT_THROW(asrt::planProgressively(movie.s, stored, movie.pixels, share, none),
               asrt::InvalidParameter);
  EXPECT_THROW(asrt::planProgressively(movie.s, stored, 0, share, making), asrt::InvalidParameter);
}

TEST(MoviePlanProgressive, ARetraceDearerThanAFrameIsLearntAndEveryFrameTraced)
{
  // Every re-trace takes a whole frame's rays for its edges alone (anti-aliasing samples, edge
  // midpoints), whatever its share: once a key has measured it, nothing is interpolated, and the
  // frames traced for it are not measured (that would interpolate them).
  SyntheticMovie movie;
  movie.slope = [](double, double) { return 1.0; };
  movie.edgeRays = movie.keyRays;
  asrt::SpacingShareModel share;
  const asrt::MoviePlan plan = movie.plan(share);
  for (std::size_t k = 0; k < plan.frames.size(); ++k)
    EXPECT_NE(plan.frames[k].method, FrameMethod::Interpolated) << "frame " << k;
  EXPECT_EQ(movie.measured, 1); // the middle key, made first on the prior
  EXPECT_DOUBLE_EQ(plan.estimatedRays, 31 * movie.keyRays);
  // With edges that cost little, the same movie interpolates, by the same measured costs.
  SyntheticMovie cheap;
  cheap.slope = movie.slope;
  cheap.edgeRays = 0.2 * cheap.keyRays;
  asrt::SpacingShareModel cheapShare;
  const asrt::MoviePlan cheapPlan = cheap.plan(cheapShare);
  EXPECT_GT(cheapPlan.keys().size(), 2u);
  EXPECT_LT(cheapPlan.keys().size(), cheapPlan.frames.size());
  EXPECT_LT(cheapPlan.estimatedRays, 0.8 * cheapPlan.directRays);
  for (const asrt::FramePlan& f : cheapPlan.frames)
    if (f.method == FrameMethod::Interpolated)
    {
      EXPECT_GE(f.rays, cheap.edgeRays);
      EXPECT_LT(f.rays, cheap.keyRays);
    }
}
