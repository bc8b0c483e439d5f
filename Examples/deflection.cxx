// Traces Schwarzschild rays of given impact parameters with every applicable method and prints the
// deflection against Darwin's exact formula (asrt::tools::schwarzschildDeflection). Usage:
// asrt_deflection [b/M ...]
#include "Measurements.h"

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

  std::printf("%-22s %10s %22s %22s %10s %8s %10s\n", "method", "b/M", "deflection (rad)",
              "Darwin (rad)", "rel.err", "steps", "ms");
  for (double b : impact)
  {
    for (const MethodInfo& m : methodTable())
    {
      if (m.family == MethodFamily::Analytic || m.name.rfind("Kerr", 0) == 0)
        continue;
      IntegratorConfig cfg;
      cfg.method = m.name;
      cfg.step = 0.01;
      const auto t0 = std::chrono::steady_clock::now();
      const tools::Deflection d = tools::schwarzschildDeflection(cfg, b);
      const double ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
      std::printf("%-22s %10.4g %22.15g %22.15g %10.2e %8ld %10.2f  %s\n", m.name.c_str(), b,
                  d.measured, d.exact, d.relativeError(), d.trace.steps, ms,
                  toString(d.trace.termination));
    }
  }
  return 0;
}
