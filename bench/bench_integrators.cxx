// Speed/accuracy trade of the ASRT integrators on a fixed set of Schwarzschild rays.
//
// Every benchmark traces the whole ray set once per iteration with one method at one step size
// (or, for the adaptive Dormand–Prince, one tolerance). The rays: M = 1, E = 1, in the equatorial
// plane, starting at R = 1000 M moving inwards, escaping at R again, with impact parameters
// b = 5.3, 6, 8, 12, 20, 50, 100, 500 M (strong to weak field; b_c = 5.196 M). The deflection of
// each ray is the swept winding plus the analytic sweep from both end radii to infinity, minus π,
// and is compared with Darwin's exact deflection.
//
// User counters (read by bench/make-report):
//   time_per_ray    CPU time per ray (s)            time_per_step   CPU time per step (s)
//   steps_per_ray   steps per ray                   evals_per_ray   gradient evaluations per ray
//   max_rel_err     max |α/α_Darwin − 1|            median_rel_err  median of the same
//   worst_b         b (M) of the ray with max_rel_err
//   max_abs_H       largest |H| at step ends over all rays
//   failed          rays that did not escape (captured, step budget, numerical failure); the
//                   error statistics are taken over the escaped rays only, and are −1 if none did
//   step / rtol     the step size h, or Dormand–Prince's relative tolerance
//   omega           Tao's coupling ω (Tao methods only)
//
// Benchmark names are <method>/h:<step>, DormandPrince54/rtol:<rtol>, and for the Tao coupling
// study <method>/omega:<ω>/h:<step> (the plain Tao ladders run at ω = 1).
//
// Usage: asrt_bench_integrators [Google Benchmark flags]; bench/run runs it and writes the report.
#include "Analytic.h"
#include "Propagator.h"
#include "RayTracer.h"
#include "Spacetime.h"

#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <exception>
#include <memory>
#include <string>
#include <vector>

namespace
{
using namespace asrt;

constexpr double Mass = 1.0;
constexpr double StartRadius = 1000.0; // start and escape radius (M)
const std::vector<double> ImpactParameters = { 5.3, 6.0, 8.0, 12.0, 20.0, 50.0, 100.0, 500.0 };

struct Ray
{
  double b;     ///< impact parameter (M)
  double truth; ///< Darwin's exact deflection (rad)
  PhasePoint start;
};

const SchwarzschildSpacetime& spacetime()
{
  static const SchwarzschildSpacetime st(Mass);
  return st;
}

const std::vector<Ray>& rays()
{
  static const std::vector<Ray> set = []
  {
    std::vector<Ray> out;
    const SchwarzschildSpacetime& st = spacetime();
    for (double b : ImpactParameters)
    {
      Ray ray;
      ray.b = b;
      ray.truth = analytic::darwinDeflection(analytic::closestApproach(b, Mass), Mass);
      // E = −p_t = 1 and L = x p_y − y p_x = b; the radial component makes p null, moving inwards.
      ray.start.x = Vec4(0.0, StartRadius, 0.0, 0.0);
      ray.start.p = completeNullMomentum(st, ray.start.x, Vec4(-1.0, 0.0, b / StartRadius, 0.0),
                                         Vec4(0.0, 1.0, 0.0, 0.0), false);
      out.push_back(ray);
    }
    return out;
  }();
  return set;
}

/// Deflection measured from a trace: winding between the end radii plus the analytic sweeps from
/// both of them out to infinity, minus π.
double measuredDeflection(const Ray& ray, const TraceResult& res)
{
  const double rEnd = spacetime().radius(res.final.x);
  return res.winding + analytic::sweepToInfinity(ray.b, Mass, StartRadius) +
         analytic::sweepToInfinity(ray.b, Mass, rEnd) - M_PI;
}

/// Repetitions (bench/run asks for 3) are summarised by their minimum too: on a shared machine the
/// fastest repetition is the least disturbed one. The accuracy counters are the same in every
/// repetition, so any statistic of them is their value.
double minimum(const std::vector<double>& v)
{
  return v.empty() ? 0.0 : *std::min_element(v.begin(), v.end());
}

std::string formatParameter(double v)
{
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

struct Case
{
  std::string name; ///< benchmark name
  std::string method;
  IntegratorConfig cfg;
  TraceOptions opts;
  bool adaptive = false;
};

void traceRaySet(benchmark::State& state, const Case& c)
{
  const SchwarzschildSpacetime& st = spacetime();
  const std::vector<Ray>& set = rays();
  std::unique_ptr<Propagator> prop;
  try
  {
    prop = makePropagator(st, c.cfg);
  }
  catch (const std::exception& e)
  {
    state.SkipWithError(e.what());
    return;
  }
  std::vector<TraceResult> results(set.size());
  for (auto _ : state)
  {
    for (std::size_t i = 0; i < set.size(); ++i)
    {
      results[i] = traceRay(st, *prop, set[i].start, c.opts);
      benchmark::DoNotOptimize(results[i]);
    }
    benchmark::ClobberMemory();
  }

  // Accuracy and work, from the last iteration (tracing is deterministic), outside the timing.
  const double n = static_cast<double>(set.size());
  long steps = 0, evaluations = 0, failed = 0;
  double maxH = 0.0, worstB = 0.0, maxErr = -1.0;
  std::vector<double> errors;
  for (std::size_t i = 0; i < set.size(); ++i)
  {
    const TraceResult& res = results[i];
    steps += res.steps;
    evaluations += res.evaluations;
    maxH = std::max(maxH, res.maxAbsH);
    if (res.termination != Termination::Escaped)
    {
      ++failed;
      continue;
    }
    const double err = std::abs(measuredDeflection(set[i], res) / set[i].truth - 1.0);
    if (!std::isfinite(err))
    {
      ++failed; // escaped with a non-finite state: count it as a failure, never drop it
      continue;
    }
    errors.push_back(err);
    if (err > maxErr)
    {
      maxErr = err;
      worstB = set[i].b;
    }
  }
  double median = -1.0;
  if (!errors.empty())
  {
    std::sort(errors.begin(), errors.end());
    const std::size_t m = errors.size() / 2;
    median = errors.size() % 2 ? errors[m] : 0.5 * (errors[m - 1] + errors[m]);
  }
  if (!std::isfinite(maxH))
  {
    maxH = -1.0; // Google Benchmark's JSON cannot hold inf or nan
  }

  using C = benchmark::Counter;
  // Inverted iteration-invariant rates: CPU time / (iterations · value), in seconds.
  state.counters["time_per_ray"] = C(n, C::kIsIterationInvariantRate | C::kInvert);
  state.counters["time_per_step"] =
    C(std::max(static_cast<double>(steps), 1.0), C::kIsIterationInvariantRate | C::kInvert);
  state.counters["steps_per_ray"] = static_cast<double>(steps) / n;
  state.counters["evals_per_ray"] = static_cast<double>(evaluations) / n;
  state.counters["max_rel_err"] = maxErr;
  state.counters["median_rel_err"] = median;
  state.counters["worst_b"] = worstB;
  state.counters["max_abs_H"] = maxH;
  state.counters["failed"] = static_cast<double>(failed);
  if (c.adaptive)
    state.counters["rtol"] = c.cfg.relativeTolerance;
  else
    state.counters["step"] = c.cfg.step;
  if (c.method.rfind("Tao", 0) == 0)
    state.counters["omega"] = c.cfg.omega;
  state.SetLabel(c.method);
}

/// The step ladder of one method: h in s (dλ = g ds, g ≈ r) for the splittings and the
/// time-transformed general rules, affine h for Tao, tolerances for Dormand–Prince.
std::vector<Case> casesFor(const MethodInfo& m)
{
  std::vector<Case> out;
  Case base;
  base.method = m.name;
  base.cfg.method = m.name;
  base.opts.escapeRadius = StartRadius;
  base.opts.maxSteps = 200000;

  std::vector<double> steps;
  if (m.name == "DormandPrince54" || m.name == "PlanarOrbit")
  {
    for (double rtol : { 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12 })
    {
      Case c = base;
      c.adaptive = true;
      c.cfg.step = 0.01; // first trial step in s; the controller takes over from there
      c.cfg.relativeTolerance = rtol;
      c.cfg.absoluteTolerance = rtol * 1e-2;
      c.name = m.name + "/rtol:" + formatParameter(rtol);
      out.push_back(c);
    }
    return out;
  }
  if (m.name.rfind("Tao", 0) == 0)
  {
    // Affine parameter: a ray of length ~2000 M takes 2000/h steps.
    base.cfg.timeTransform = false;
    base.opts.maxSteps = 2000000;
    steps = { 3.0, 1.0, 0.3, 0.1, 0.03, 0.01 };
  }
  else if (m.family == MethodFamily::General && m.order >= 6)
  {
    // Gauss–Legendre 6 reaches round-off by h = 0.01; smaller steps only cost.
    steps = { 0.2, 0.1, 0.05, 0.02, 0.01, 0.005 };
  }
  else
  {
    steps = { 0.2, 0.1, 0.05, 0.02, 0.01, 0.005, 0.002, 0.001 };
  }
  for (double h : steps)
  {
    Case c = base;
    c.cfg.step = h;
    c.name = m.name + "/h:" + formatParameter(h);
    out.push_back(c);
  }
  if (m.name == "Tao4")
  {
    // The coupling study: ω against the default ω = 1 of the ladder above, at moderate steps.
    for (double omega : { 0.3, 3.0, 10.0, 30.0 })
    {
      for (double h : { 1.0, 0.3, 0.1 })
      {
        Case c = base;
        c.cfg.step = h;
        c.cfg.omega = omega;
        c.name = m.name + "/omega:" + formatParameter(omega) + "/h:" + formatParameter(h);
        out.push_back(c);
      }
    }
  }
  return out;
}
}

int main(int argc, char** argv)
{
  // Methods that model Schwarzschild: not the flat-space straight line, not the Kerr splittings.
  for (const MethodInfo& m : methodTable())
  {
    if (m.family == MethodFamily::Analytic || m.name.rfind("Kerr", 0) == 0)
      continue;
    for (const Case& c : casesFor(m))
    {
      benchmark::RegisterBenchmark(c.name.c_str(), [c](benchmark::State& s) { traceRaySet(s, c); })
        ->Unit(benchmark::kMillisecond)
        ->ComputeStatistics("min", minimum);
    }
  }
  std::string impact;
  for (double b : ImpactParameters)
    impact += (impact.empty() ? "" : ", ") + formatParameter(b);
  benchmark::AddCustomContext("asrt_impact_parameters", impact);
  benchmark::AddCustomContext("asrt_start_radius", formatParameter(StartRadius));
  // What "auto" picks for this spacetime, so the report can place the default on the trade.
  benchmark::AddCustomContext("asrt_default_method", defaultMethod(spacetime()));
  benchmark::AddCustomContext("asrt_default_step", formatParameter(IntegratorConfig{}.step));
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv))
    return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
