// Traces Schwarzschild rays of given impact parameters with every applicable method and prints the
// deflection against Darwin's exact formula. Usage: asrt_deflection [b/M ...]
#include "Analytic.h"
#include "RayTracer.h"
#include "Spacetime.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <vector>

using namespace asrt;

int main(int argc, char* argv[])
{
  std::vector<double> impact;
  for (int i = 1; i < argc; ++i)
  {
    char* end = nullptr;
    const double b = std::strtod(argv[i], &end);
    if (end == argv[i] || !(b > 3.0 * std::sqrt(3.0)))
    {
      std::fprintf(stderr, "asrt_deflection: '%s' is not an impact parameter above b_c = 5.196 M\n",
                   argv[i]);
      return 2;
    }
    impact.push_back(b);
  }
  if (impact.empty())
    impact = { 5.3, 10.0, 100.0 };

  const SchwarzschildSpacetime st(1.0);
  std::printf("%-22s %10s %22s %22s %10s %8s %10s\n", "method", "b/M", "deflection (rad)",
              "Darwin (rad)", "rel.err", "steps", "ms");
  for (double b : impact)
  {
    const double truth = analytic::darwinDeflection(analytic::closestApproach(b, 1.0), 1.0);
    const double R = std::max(1000.0, 20.0 * b);
    PhasePoint z;
    z.x = Vec4(0, R, 0, 0);
    z.p = completeNullMomentum(st, z.x, Vec4(-1, 0, b / R, 0), Vec4(0, 1, 0, 0), false);
    for (const MethodInfo& m : methodTable())
    {
      if (m.family == MethodFamily::Analytic || m.name.rfind("Kerr", 0) == 0)
        continue;
      IntegratorConfig cfg;
      cfg.method = m.name;
      cfg.step = m.family == MethodFamily::Splitting ? 0.01 : 0.01;
      TraceOptions opts;
      opts.escapeRadius = R;
      auto prop = makePropagator(st, cfg);
      const auto t0 = std::chrono::steady_clock::now();
      const TraceResult res = traceRay(st, *prop, z, opts);
      const double ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
      const double measured = res.winding + analytic::sweepToInfinity(b, 1.0, R) +
                              analytic::sweepToInfinity(b, 1.0, res.final.x.tail<3>().norm()) -
                              M_PI;
      std::printf("%-22s %10.4g %22.15g %22.15g %10.2e %8ld %10.2f  %s\n", m.name.c_str(), b,
                  measured, truth, std::abs(measured / truth - 1.0), res.steps, ms,
                  toString(res.termination));
    }
  }
  return 0;
}
