#include "PathInterpolation.h"

#include "ErrorEstimate.h"
#include "FrameTracer.h"
#include "RecordHashing.h"
#include "SettingsError.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <string>

// Completing a frame predicted along a path to a quality target (completePathFrame): probes that
// calibrate each way of predicting's estimate, the order of re-tracing and its bound, the edges
// traced pixels show that the prediction missed, and the strata of the keys' settings' error
// traced with the rendering that judges the target.
namespace asrt
{
namespace
{
[[noreturn]] void invalid(const std::string& what)
{
  throw InvalidParameter("path interpolation: " + what);
}

/// Probes a way of predicting gets at least, however few its pixels' share (all if fewer): a
/// sample of the frame's fraction alone leaves a way of predicting that covers a few per cent of
/// the frame with a handful of probes, too few to see errors that are rare but large.
constexpr std::size_t kProbesPerMethod = 32;
/// The probes below a place in the re-tracing order that stand for the untraced pixels there, at
/// least (the lowest ranked of their way of predicting when fewer lie below).
constexpr std::size_t kTailProbes = 16;
/// Standard errors added to a tail's mean probe error: one frame in forty or so exceeds it.
constexpr double kConfidence = 2.0;
/// The least scale of edge blends that the keys' leave-one-out errors rank (those not ranked have
/// a floor of 1): their errors are rare and large, and a sample of probes that misses them sets the
/// ratio far too low (on the mass ramp at 40 dB, 0.004 from 32 probes where the untraced edge
/// blends' own ratio was 0.023, and the frame fell 1.5 dB below its target against converged). A
/// sixteenth: what an edge a quarter of a pixel further than the keys put it changes.
constexpr double kRankedEdgeBlendScale = 1.0 / 16.0;
/// The largest estimate (squared colour error summed over the channels, levels² of 255) of a
/// predicted pixel that a re-traced neighbour reads instead of tracing it: a level a channel. On
/// the mass ramp's 96 × 96 test frame that left every re-traced colour within 1.2 levels of the
/// traced frame's; reading every predicted neighbour, one of them was 53 levels off (an edge
/// that the prediction put a pixel away).
constexpr float kGivenNeighbourError = 3.0f;

std::uint64_t pixelHash(std::uint64_t x)
{
  x += 0x9e3779b97f4a7c15ULL; // splitmix64
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

/// The probes: the frame's fixed pseudo-random share, topped up per way of predicting to
/// kProbesPerMethod of its pixels (the lowest hashes among them), in increasing order.
std::vector<std::int32_t> stratifiedProbes(const std::vector<std::uint8_t>& methods,
                                           double fraction)
{
  const std::size_t n = methods.size();
  std::vector<std::int32_t> probes = probePixels(n, fraction, 64, 0x9e3779b97f4a7c15ULL);
  std::vector<char> chosen(n, 0);
  std::size_t have[kPathMethodCount] = {};
  for (std::int32_t p : probes)
  {
    chosen[static_cast<std::size_t>(p)] = 1;
    ++have[methods[static_cast<std::size_t>(p)]];
  }
  for (int m = 0; m < kPathMethodCount; ++m)
  {
    if (!isPrediction(static_cast<std::uint8_t>(m)) || have[m] >= kProbesPerMethod)
      continue;
    std::vector<std::pair<std::uint64_t, std::int32_t>> pool;
    for (std::size_t p = 0; p < n; ++p)
      if (methods[p] == m && !chosen[p])
        pool.emplace_back(pixelHash(p), static_cast<std::int32_t>(p));
    const std::size_t more = std::min(pool.size(), kProbesPerMethod - have[m]);
    std::partial_sort(pool.begin(), pool.begin() + static_cast<std::ptrdiff_t>(more), pool.end());
    for (std::size_t k = 0; k < more; ++k)
      probes.push_back(pool[k].second);
  }
  std::sort(probes.begin(), probes.end());
  return probes;
}

/// Sums of the true errors of a sample of probes.
struct ProbeSample
{
  double count = 0, sum = 0, sum2 = 0;
  void add(double e)
  {
    count += 1;
    sum += e;
    sum2 += e * e;
  }
  /// A bound on the mean error of the pixels the sample stands for: its mean plus kConfidence
  /// standard errors, and one more probe of error `missed` (the typical size of an error of this
  /// way of predicting): a sample in which no probe erred does not show that none of the pixels
  /// does, only that few do.
  double meanBound(double missed) const
  {
    if (count <= 0)
      return missed;
    const double mean = sum / count;
    const double variance = std::max(0.0, sum2 / count - mean * mean);
    return (sum + missed) / (count + 1) + kConfidence * std::sqrt(variance / count);
  }
};

/// The least scale of a way of predicting's estimates: its order of re-tracing kept where its
/// probes were all exact.
constexpr double kLeastScale = 1.0 / 1024.0;
/// The least scale of linear pixels' estimates (two keys alone agree: the outer keys show another
/// surface). Their estimate, the keys' colour step and the texture between the prediction and the
/// nearer key, is most often far above their error (their probes' ratio 0.0002–0.014 on the four
/// benchmark paths), but a few miss by far more than that ratio says: on Fig. 1's orbit, the last
/// interval (3 keys, 89°) at 40 dB, 1 025 linear pixels held 5.8 of the frame's 9.0 levels² against
/// 8 × 8 and it scored 38.6 dB, estimated 40.6. A sixteenth: 41.4 dB, estimated 40.0, for 0–0.8 %
/// more of the four paths' frames re-traced.
constexpr double kLinearLeastScale = 1.0 / 16.0;
}

double estimateScale(PathMethod m, const std::vector<ProbePair>& probes, EstimateScaling scaling,
                     bool edgeBlendsRanked)
{
  double estimated = 0, erred = 0;
  for (const ProbePair& q : probes)
  {
    estimated += q.estimate;
    erred += q.error;
  }
  if (!(estimated > 0))
    return 1.0;
  const double ratio = erred / estimated;
  if (scaling == EstimateScaling::AtLeastOne)
    return std::max(1.0, ratio);
  const double n = static_cast<double>(probes.size());
  double spread = 0;
  for (const ProbePair& q : probes)
    spread += (q.error - ratio * q.estimate) * (q.error - ratio * q.estimate);
  const double standardError = n > 1 ? std::sqrt(spread / (n - 1) / n) / (estimated / n) : ratio;
  const double raised = ratio + kConfidence * standardError;
  // Moved edges' and edge blends' errors are rare and large: a ratio their probes happen to set
  // low would leave them untraced. Where the keys' leave-one-out errors put the edge blends first,
  // a sixteenth is enough; so it is for linear pixels (kLinearLeastScale).
  double least = kLeastScale;
  if (m == PathMethod::MovedEdge)
    least = 1.0;
  else if (m == PathMethod::EdgeBlend)
    least = edgeBlendsRanked ? kRankedEdgeBlendScale : 1.0;
  else if (m == PathMethod::Linear)
    least = kLinearLeastScale;
  // n probes that erred little do not show a way's large errors to be rarer than 3 pixels in n:
  // a rate the n would all have missed one time in twenty (the rule of three, 95 % one-sided).
  // Below it, a way whose rare large errors its probes happened to miss was scaled away: on
  // Fig. 1's orbit at 40 dB (61 frames, keys 6° apart), one frame's quadratic pixels where the
  // checkers' colour flipped between the two orders, estimated 30 000–85 000 levels² and in truth
  // off by 8 000 on average, were scaled by 0.002 (its 32 probes' ratio: the highest of them,
  // estimated 81 500, was not wrong) and left untraced; the frame scored 35.3 dB against converged.
  // Floored at 3 / 32: 39.1 dB, for 0.4 % more rays over that movie and 0.5–0.7 % at 35 dB on the
  // mass ramp and that orbit.
  least = std::max(least, 3.0 / static_cast<double>(probes.size()));
  return std::max(least, raised);
}

namespace
{

/// A probe: where its calibrated estimate places it in the order of re-tracing, its way of
/// predicting and its true error.
struct PlacedProbe
{
  std::size_t at = 0;
  int method = 0;
  double error = 0;
};

/// What re-tracing the first k of `rest` (the order of re-tracing) leaves, for every k: per way of
/// predicting, the larger of its calibrated estimates' sum and its probes' bound times its
/// untraced pixels, summed. The probes placed at or after k stand for those pixels; where fewer
/// than kTailProbes lie there, the next ones before k join them (higher estimates: an over-
/// rather than an under-statement).
std::vector<double> remainingError(const std::vector<std::int32_t>& rest,
                                   const std::vector<double>& calibrated,
                                   const std::vector<std::uint8_t>& methods,
                                   std::vector<PlacedProbe> probes)
{
  constexpr int M = kPathMethodCount;
  std::stable_sort(probes.begin(), probes.end(),
                   [](const PlacedProbe& a, const PlacedProbe& b) { return a.at > b.at; });
  // The typical error of each way of predicting where it errs (else the frame's, else a level a
  // channel): what a probe that the sample happened to miss would have shown.
  ProbeSample erring[M], erringAll, lowest[M];
  for (const PlacedProbe& q : probes)
  {
    if (q.error > 0)
    {
      erring[q.method].add(q.error);
      erringAll.add(q.error);
    }
    if (lowest[q.method].count < kTailProbes)
      lowest[q.method].add(q.error);
  }
  double missed[M];
  for (int m = 0; m < M; ++m)
    missed[m] = erring[m].count > 0   ? erring[m].sum / erring[m].count
                : erringAll.count > 0 ? erringAll.sum / erringAll.count
                                      : 3.0;
  std::vector<double> remaining(rest.size() + 1, 0.0);
  double count[M] = {}, left[M] = {};
  ProbeSample tail[M];
  std::size_t next = 0;
  for (std::size_t k = rest.size() + 1; k-- > 0;)
  {
    if (k < rest.size())
    {
      const std::size_t p = static_cast<std::size_t>(rest[k]);
      count[methods[p]] += 1;
      left[methods[p]] += calibrated[p];
    }
    for (; next < probes.size() && probes[next].at >= k; ++next)
      tail[probes[next].method].add(probes[next].error);
    double sum = 0;
    for (int m = 0; m < M; ++m)
      if (count[m] > 0)
      {
        const ProbeSample& sample = tail[m].count >= kTailProbes ? tail[m] : lowest[m];
        sum += std::max(left[m], count[m] * sample.meanBound(missed[m]));
      }
    remaining[k] = sum;
  }
  return remaining;
}

/// Pixels within this many (either way) of a pixel whose traced neighbour contradicts it, and
/// predicted to show the same surface, are traced with it: each round of following costs a pass of
/// the tracer (a parallel region, and the halo of neighbours its pixels' anti-aliasing reads),
/// which on a loaded machine costs as much as a few hundred pixels; on Fig. 1's 90° orbit, 31
/// frames at 200 × 200, a reach of 2 instead of 0 took 27 such passes instead of 67 for 3 718
/// pixels instead of 2 686.
constexpr int kFollowReach = 2;

/// The untraced predicted pixels p next to (8-neighbours of) the traced pixels q of `from` where
/// q shows another surface than its own prediction (`predicted`, as the frame was before any
/// re-trace) and than p's, and no inner key showed q's surface at q with p's at p (an edge runs
/// between them at t that neither the keys nor the prediction put there), with the pixels within
/// kFollowReach of them predicted to show what they show, in increasing order.
std::vector<std::int32_t> contradictedNeighbours(const PathFrame& frame,
                                                 const std::vector<std::int32_t>& from,
                                                 const std::vector<char>& traced,
                                                 const std::vector<std::uint8_t>& methods,
                                                 const std::vector<PathSurface>& predicted)
{
  const int w = frame.width, h = frame.height;
  std::vector<char> chosen(frame.records.size(), 0);
  std::vector<std::int32_t> out;
  for (std::int32_t q : from)
  {
    const std::size_t uq = static_cast<std::size_t>(q);
    const PathSurface atQ = surfaceOf(frame.records[uq]);
    // Traced as predicted: the prediction's edges around q stand where it put them.
    if (sameSurface(predicted[uq], atQ))
      continue;
    const int i = q % w, j = q / w;
    for (int dj = -1; dj <= 1; ++dj)
      for (int di = -1; di <= 1; ++di)
      {
        const int x = i + di, y = j + dj;
        if (x < 0 || x >= w || y < 0 || y >= h)
          continue;
        const std::size_t p = static_cast<std::size_t>(y) * w + x;
        if (traced[p] || chosen[p] || !isPrediction(methods[p]))
          continue;
        const PathSurface atP = surfaceOf(frame.records[p]);
        if (sameSurface(atQ, atP))
          continue;
        bool seen = false;
        for (const std::vector<PathSurface>& key : frame.innerKeys)
          seen = seen || (!key.empty() && sameSurface(key[uq], atQ) && sameSurface(key[p], atP));
        if (!seen)
        {
          chosen[p] = 1;
          out.push_back(static_cast<std::int32_t>(p));
        }
      }
  }
  // The surface at q may reach further into what the prediction shows alike around p.
  const std::size_t found = out.size();
  for (std::size_t k = 0; k < found; ++k)
  {
    const std::size_t c = static_cast<std::size_t>(out[k]);
    const PathSurface atC = surfaceOf(frame.records[c]);
    const int i = out[k] % w, j = out[k] / w;
    for (int dj = -kFollowReach; dj <= kFollowReach; ++dj)
      for (int di = -kFollowReach; di <= kFollowReach; ++di)
      {
        const int x = i + di, y = j + dj;
        if (x < 0 || x >= w || y < 0 || y >= h)
          continue;
        const std::size_t p = static_cast<std::size_t>(y) * w + x;
        if (traced[p] || chosen[p] || !isPrediction(methods[p]) ||
            !sameSurface(surfaceOf(frame.records[p]), atC))
          continue;
        chosen[p] = 1;
        out.push_back(static_cast<std::int32_t>(p));
      }
  }
  std::sort(out.begin(), out.end());
  return out;
}
}

PathCompletion completePathFrame(PathFrame& frame, const FrameTracer& tracer, double targetDb,
                                 double probeFraction, double settingsMse, EstimateScaling scaling)
{
  const CameraParameters& cam = tracer.description().camera;
  if (cam.width != frame.width || cam.height != frame.height)
    invalid("the tracer's frame is " + std::to_string(cam.width) + " x " +
            std::to_string(cam.height) + ", the path frame " + std::to_string(frame.width) + " x " +
            std::to_string(frame.height));
  return completePathFrame(frame, pixelTracerOf(tracer), targetDb, probeFraction, settingsMse,
                           scaling);
}

PixelTracer pixelTracerOf(const FrameTracer& tracer)
{
  // The lists of one frame border each other (a list's edge neighbours are often asked for
  // later): their centre rays are traced once.
  auto kept = std::make_shared<CentreRays>();
  return [&tracer, kept](const std::vector<std::pair<int, int>>& ij,
                         const std::vector<JacobianSample>& border)
  {
    const std::int64_t before = tracer.raysIntegrated();
    TracedPixels out;
    out.records = tracer.tracePixelsBeside(ij, border, kept.get());
    out.rays = static_cast<double>(tracer.raysIntegrated() - before);
    return out;
  };
}

namespace
{
/// The predicted pixels not traced yet, worst calibrated estimate first (ties by index), and what
/// re-tracing the first k of them leaves: mse[k], a mean squared error per channel over the frame.
struct UntracedOrder
{
  std::vector<std::int32_t> rest;
  std::vector<double> mse;
};

UntracedOrder untracedOrder(const std::vector<char>& traced,
                            const std::vector<std::uint8_t>& methods,
                            const std::vector<double>& calibrated,
                            const std::vector<std::int32_t>& probes,
                            const std::vector<double>& probeError)
{
  const std::size_t n = traced.size();
  auto worse = [&](std::int32_t a, std::int32_t b)
  {
    const double ca = calibrated[static_cast<std::size_t>(a)];
    const double cb = calibrated[static_cast<std::size_t>(b)];
    return ca != cb ? ca > cb : a < b;
  };
  // Sorted as (calibrated, pixel) pairs side by side, not indices that look their values up.
  std::vector<std::pair<double, std::int32_t>> order;
  for (std::size_t p = 0; p < n; ++p)
    if (!traced[p] && methods[p] != static_cast<std::uint8_t>(PathMethod::Key))
      order.emplace_back(calibrated[p], static_cast<std::int32_t>(p));
  std::sort(order.begin(), order.end(),
            [](const std::pair<double, std::int32_t>& a, const std::pair<double, std::int32_t>& b)
            { return a.first != b.first ? a.first > b.first : a.second < b.second; });
  UntracedOrder out;
  out.rest.resize(order.size());
  for (std::size_t k = 0; k < order.size(); ++k)
    out.rest[k] = order[k].second;
  // What re-tracing the first k of `rest` leaves is bounded twice, per way of predicting: by the
  // calibrated estimates, and by the probes' own errors (each probe stands for the untraced pixels
  // about its place in the order), with a confidence margin, so that a sample that happened to
  // miss a way's rare large errors does not pass for a clean one.
  std::vector<PlacedProbe> placed;
  for (std::size_t q = 0; q < probes.size(); ++q)
    if (probeError[q] >= 0)
      placed.push_back({ static_cast<std::size_t>(
                           std::lower_bound(out.rest.begin(), out.rest.end(), probes[q], worse) -
                           out.rest.begin()),
                         methods[static_cast<std::size_t>(probes[q])], probeError[q] });
  out.mse = remainingError(out.rest, calibrated, methods, placed);
  for (double& e : out.mse)
    e /= 3.0 * static_cast<double>(n);
  return out;
}

/// The fewest of the order's first pixels whose re-tracing leaves at most `budgetMse`; all of them
/// where none does.
std::size_t fewestWithin(const UntracedOrder& u, double budgetMse)
{
  for (std::size_t k = 0; k <= u.rest.size(); ++k)
    if (u.mse[k] <= budgetMse)
      return k;
  return u.rest.size();
}

/// The shares of the target's error the settings' strata left unrefined may keep, among which
/// cheapestRefinement chooses (above the last, the prediction would be held to less than a
/// quarter of the target's error).
constexpr double kSettingsShares[] = { 0.25, 0.375, 0.5, 0.625, kRefineSettingsAbove };

/// The strata to trace converged: of the shares above, the one for which tracing them and then
/// re-tracing, with the keys' settings, the predicted pixels the rest of the target needs
/// (`untraced`, before any is refined) takes the fewest rays by estimate (`raysPerRetraced` a
/// re-traced pixel, as the frame's first pixels took; the converged rendering's a refined one, a
/// partly refined stratum counted by its share). `strata`: the frame's (settingsStrata).
RefinedStrata cheapestRefinement(const SettingsRefinement& refinement,
                                 const std::vector<std::uint8_t>& strata,
                                 const UntracedOrder& untraced, double targetMse,
                                 double raysPerRetraced)
{
  double pixels[kSettingsStrata] = {};
  for (std::uint8_t k : strata)
    pixels[k] += 1;
  RefinedStrata best;
  double bestRays = std::numeric_limits<double>::infinity();
  for (double share : kSettingsShares)
  {
    const RefinedStrata r = strataToRefine(refinement.settings, share * targetMse);
    double refined = r.partial >= 0 ? r.fraction * pixels[r.partial] : 0.0;
    for (int k = 0; k < kSettingsStrata; ++k)
      refined += (r.whole & (1u << k)) ? pixels[k] : 0.0;
    const double left = refinement.settings.mseBoundWithout(r);
    const double rays =
      refined * refinement.raysPerPixel +
      static_cast<double>(fewestWithin(untraced, std::max(targetMse - left, 0.25 * targetMse))) *
        raysPerRetraced;
    if (rays < bestRays)
    {
      bestRays = rays;
      best = r;
    }
  }
  return best;
}

PathCompletion completeFrame(PathFrame& frame, const PixelTracer& tracePixels, double targetDb,
                             double probeFraction, double settingsMse, EstimateScaling scaling,
                             const SettingsRefinement* refinement)
{
  if (!(targetDb > 0.0 && targetDb <= kMaxQualityTargetDb))
  {
    std::ostringstream os;
    os << "path interpolation: the quality target must lie in (0, " << kMaxQualityTargetDb
       << "] dB, got " << targetDb;
    throw InvalidParameter(os.str());
  }
  if (!(settingsMse >= 0.0) || std::isinf(settingsMse))
    invalid("the settings' own error must be a finite mean squared error of 0 or more, got " +
            std::to_string(settingsMse));
  const std::size_t n = frame.records.size();
  PathCompletion done;
  done.estimatedPsnr = psnrOfMse(settingsMse);
  if (frame.counts()[static_cast<std::size_t>(PathMethod::Key)] == n)
    return done;                                       // a key frame: nothing predicted
  const std::vector<float> estimates = frame.estimate; // as predicted, before any re-trace
  const std::vector<std::uint8_t> methods = frame.method;
  std::vector<char> traced(n, 0);
  // The pixels of `pixels` not traced yet (all of them where `converged`) traced with
  // `tracePixels`, or with the converged rendering (SettingsRefinement).
  auto traceList = [&](const std::vector<std::int32_t>& pixels, bool converged)
  {
    std::vector<std::pair<int, int>> ij;
    std::vector<std::int32_t> which;
    for (std::int32_t p : pixels)
      if (converged || !traced[static_cast<std::size_t>(p)])
      {
        done.retraced += !traced[static_cast<std::size_t>(p)];
        traced[static_cast<std::size_t>(p)] = 1;
        which.push_back(p);
        ij.emplace_back(p % frame.width, p / frame.width);
      }
    // The list's edge neighbours that the frame vouches for are given, not traced: those traced
    // before, and predicted ones whose estimate is within a level a channel (kGivenNeighbourError).
    // Those, a traced ray would show within that level; the others are traced and dropped.
    std::vector<JacobianSample> border;
    for (const auto& [i, j] : edgeNeighbours(ij, frame.width, frame.height))
    {
      const std::size_t q = static_cast<std::size_t>(j) * frame.width + i;
      if (!traced[q] && !(frame.estimate[q] <= kGivenNeighbourError))
        continue;
      JacobianSample s = jacobianSample(frame.records[q]);
      s.i = i;
      s.j = j;
      border.push_back(s);
    }
    const TracedPixels got = converged ? refinement->converged(ij, {}) : tracePixels(ij, border);
    const std::vector<RayRecord>& records = got.records;
    done.raysTraced += got.rays;
    if (records.size() != ij.size())
      invalid("the pixel tracer returned " + std::to_string(records.size()) + " records for " +
              std::to_string(ij.size()) + " pixels");
    for (std::size_t k = 0; k < which.size(); ++k)
    {
      const std::size_t p = static_cast<std::size_t>(which[k]);
      frame.records[p] = records[k];
      frame.estimate[p] = 0.0f;
      frame.method[p] = static_cast<std::uint8_t>(PathMethod::Retraced);
    }
    if (converged)
      done.refined += which.size();
  };
  auto trace = [&](const std::vector<std::int32_t>& pixels) { traceList(pixels, false); };

  // The pixels the keys cannot vouch for, and the probes, in one pass.
  const std::vector<std::int32_t> probes = stratifiedProbes(methods, probeFraction);
  std::vector<std::int32_t> first;
  for (std::size_t p = 0; p < n; ++p)
    if (methods[p] == static_cast<std::uint8_t>(PathMethod::Retrace))
      first.push_back(static_cast<std::int32_t>(p));
  done.mustRetrace = first.size();
  std::vector<RayRecord> predicted;
  for (std::int32_t p : probes)
    predicted.push_back(frame.records[static_cast<std::size_t>(p)]);
  first.insert(first.end(), probes.begin(), probes.end());
  std::vector<PathSurface> predictedSurfaces(n);
  for (std::size_t p = 0; p < n; ++p)
    predictedSurfaces[p] = surfaceOf(frame.records[p]);
  trace(first);
  done.probes = probes.size();
  // The traced pixels show where the edges lie at t. A predicted neighbour that shows another
  // surface than a traced pixel, where neither inner key showed those two surfaces on those two
  // pixels, has an edge beside it that the keys did not see there (an object that sweeps across
  // pixels both keys show behind it, as the tip of a moving silhouette does): such pixels are
  // traced too, and their neighbours judged in turn, until the traced edges close.
  for (std::vector<std::int32_t> from =
         contradictedNeighbours(frame, first, traced, methods, predictedSurfaces);
       !from.empty();
       from = contradictedNeighbours(frame, from, traced, methods, predictedSurfaces))
  {
    done.followed += from.size();
    trace(from);
  }

  // Each way of predicting has its own scale, from its probes' true errors against their
  // estimates (estimateScale). Where a way's estimate misses errors altogether, its probes' bound
  // below sees them.
  std::vector<ProbePair> pairs[kPathMethodCount];
  std::vector<double> probeError(probes.size(), -1.0); // −1: not a prediction
  for (std::size_t q = 0; q < probes.size(); ++q)
  {
    const std::size_t p = static_cast<std::size_t>(probes[q]);
    if (!isPrediction(methods[p]))
      continue;
    probeError[q] = colorError2(predicted[q].color, frame.records[p].color);
    pairs[methods[p]].push_back({ estimates[p], probeError[q] });
  }
  double scale[kPathMethodCount];
  for (int m = 0; m < kPathMethodCount; ++m)
    scale[m] =
      estimateScale(static_cast<PathMethod>(m), pairs[m], scaling, frame.leaveOneOutWeighed);
  std::vector<double> calibrated(n, 0.0);
  for (std::size_t p = 0; p < n; ++p)
    if (isPrediction(methods[p]))
      calibrated[p] = scale[methods[p]] * estimates[p];
  // Where the keys' settings alone leave the frame short of the target, the strata that hold
  // their error are traced with the converged rendering (SettingsRefinement), after the probes'
  // errors are taken: those measure the prediction against the keys' settings.
  const double targetMse = mseOfPsnr(targetDb);
  double settingsLeft = settingsMse;
  UntracedOrder untraced = untracedOrder(traced, methods, calibrated, probes, probeError);
  if (refinement && settingsFallShort(refinement->settings, targetDb))
  {
    const double raysPerRetraced =
      done.retraced > 0 ? done.raysTraced / static_cast<double>(done.retraced) : 1.0;
    const std::vector<std::uint8_t> strata = settingsStrata(frame.records);
    const RefinedStrata refined =
      cheapestRefinement(*refinement, strata, untraced, targetMse, raysPerRetraced);
    traceList(pixelsOfStrata(strata, refined), true);
    settingsLeft = refinement->settings.mseBoundWithout(refined);
    untraced = untracedOrder(traced, methods, calibrated, probes, probeError);
  }
  // The frame's error against the converged picture is what the prediction leaves against the
  // frame traced at t plus that frame's own error (the settings'). Where the settings leave the
  // prediction less than a quarter of the target's error, the prediction is held to that quarter:
  // re-tracing with these settings cannot lift the frame above them.
  const double budget = std::max(targetMse - settingsLeft, 0.25 * targetMse);
  const std::size_t count = fewestWithin(untraced, budget);
  const std::vector<std::int32_t>& rest = untraced.rest;
  done.estimatedPsnr = psnrOfMse(untraced.mse[count] + settingsLeft);
  trace(std::vector<std::int32_t>(rest.begin(), rest.begin() + static_cast<std::ptrdiff_t>(count)));
  return done;
}
}

PathCompletion completePathFrame(PathFrame& frame, const PixelTracer& tracePixels, double targetDb,
                                 double probeFraction, double settingsMse, EstimateScaling scaling)
{
  return completeFrame(frame, tracePixels, targetDb, probeFraction, settingsMse, scaling, nullptr);
}

PathCompletion completePathFrame(PathFrame& frame, const PixelTracer& tracePixels, double targetDb,
                                 double probeFraction, const SettingsRefinement& refinement,
                                 EstimateScaling scaling)
{
  if (!refinement.converged)
    invalid("the settings' refinement has no converged pixel tracer");
  return completeFrame(frame, tracePixels, targetDb, probeFraction, refinement.settings.mseBound(),
                       scaling, &refinement);
}
}
