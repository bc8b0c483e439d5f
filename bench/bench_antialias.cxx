// Anti-aliasing: quality against cost on whole frames. Every scene at 200×200 (and, optionally, at
// 1920×1080) with each rendering mode and cap, against a supersampled reference of the same view
// traced in the same run; then the temporal flicker of a camera orbit around Fig. 1. Prints a
// Markdown section for bench/REPORT.md, and with --plot-data the 200×200 points for
// bench/plot-antialias.
// Usage: asrt_bench_antialias scene.json... [--no-hd] [--small WxH] [--hd WxH] [--orbit-frames N]
//                             [--repetitions N] [--plot-data FILE]
// ASRT_BENCH_AA_ONLY=a,b runs only the parts whose name (the scene file's, or "orbit") contains
// one of the substrings.
#include "CameraOrbit.h"
#include "FrameTracer.h"
#include "GeodesicSceneLoading.h"
#include "ImageQuality.h"
#include "SceneFile.h"

#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

using namespace asrt;

namespace
{
// The goals: an anti-aliased frame close to the reference at little more than one ray's cost.
constexpr double kGoalPsnr = 38.0;         ///< dB
constexpr double kGoalOffFraction = 0.005; ///< of pixels with a channel off by more than kOffBy
constexpr int kOffBy = 32;                 ///< 8-bit levels
constexpr double kGoalCost = 2.0;          ///< rays and wall time, relative to one ray a pixel
constexpr double kGoalFlicker = 0.10;      ///< the orbit's flicker within 10 % of the reference's

double now()
{
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

/// Standard output of a command, empty if it cannot run (for the machine line and the commit).
std::string commandOutput(const char* command)
{
  std::string out;
  if (FILE* p = popen(command, "r"))
  {
    char buf[512];
    while (std::fgets(buf, sizeof buf, p))
      out += buf;
    pclose(p);
  }
  return out;
}

/// The machine as bench/make-report describes it (lscpu's model, CPUs, cores and sockets).
std::string machine()
{
  std::map<std::string, std::string> info;
  std::istringstream lines(commandOutput("lscpu 2>/dev/null"));
  for (std::string line; std::getline(lines, line);)
  {
    const auto colon = line.find(':');
    if (colon == std::string::npos)
      continue;
    const auto value = line.find_first_not_of(" \t", colon + 1);
    info[line.substr(0, colon)] = value == std::string::npos ? "" : line.substr(value);
  }
  std::string s = (info.count("Model name") ? info["Model name"] : "unknown CPU") + " — " +
                  (info.count("CPU(s)") ? info["CPU(s)"] : "?") + " CPU(s)";
  if (info.count("Core(s) per socket") && info.count("Socket(s)"))
    s += ", " + info["Core(s) per socket"] + " core(s) per socket × " + info["Socket(s)"] +
         " socket(s)";
  if (info.count("Thread(s) per core"))
    s += ", " + info["Thread(s) per core"] + " thread(s) per core";
  if (info.count("Hypervisor vendor"))
    s += " (virtualised, " + info["Hypervisor vendor"] + ")";
  return s;
}

double loadAverage()
{
  double load[3] = { -1, -1, -1 };
  return getloadavg(load, 3) < 0 ? -1 : load[0];
}

/// Whether a part of the run is wanted: ASRT_BENCH_AA_ONLY unset, or one of its comma-separated
/// substrings occurs in the part's name.
bool wanted(const std::string& name)
{
  const char* only = std::getenv("ASRT_BENCH_AA_ONLY");
  if (!only || !*only)
    return true;
  std::istringstream list(only);
  for (std::string part; std::getline(list, part, ',');)
    if (!part.empty() && name.find(part) != std::string::npos)
      return true;
  return false;
}

AntialiasOptions options(AntialiasMode mode, int cap = 16, int supersample = 1,
                         double threshold = 1.0)
{
  AntialiasOptions o;
  o.mode = mode;
  o.maxRaysPerPixel = cap;
  o.supersample = supersample;
  o.colorThreshold = threshold;
  return o;
}

/// What a configuration is, in the table's words (naming the preset it equals, if any).
std::string describe(const AntialiasOptions& o)
{
  char s[128];
  if (o.supersample > 1)
    std::snprintf(s, sizeof s, "%s, supersample %d×%d", toString(o.mode), o.supersample,
                  o.supersample);
  else if (o.mode == AntialiasMode::Adaptive && o.colorThreshold < 1.0)
    std::snprintf(s, sizeof s, "adaptive, cap %d, colour threshold %g", o.maxRaysPerPixel,
                  o.colorThreshold);
  else if (o.mode == AntialiasMode::Adaptive)
    std::snprintf(s, sizeof s, "adaptive, cap %d", o.maxRaysPerPixel);
  else
    std::snprintf(s, sizeof s, "%s", toString(o.mode));
  std::string label = s;
  for (const char* preset : { "fast", "balanced", "accurate" })
  {
    const AntialiasOptions p = renderingPreset(preset);
    // Options the mode ignores do not tell configurations apart.
    const bool same =
      p.mode == o.mode && p.supersample == o.supersample &&
      (o.mode != AntialiasMode::Adaptive ||
       (p.maxRaysPerPixel == o.maxRaysPerPixel && p.colorThreshold == o.colorThreshold));
    if (same)
      label += std::string(" (preset `") + preset + "`)";
  }
  return label;
}

/// A traced frame as the PNG stores it, and what it cost.
struct Frame
{
  int width = 0, height = 0;
  std::vector<std::uint8_t> rgb; ///< row-major from the bottom-left, 3 bytes a pixel
  double rays = 0;               ///< Σ raysPerPixel
  double seconds = 0;            ///< best wall time of the repetitions
};

/// One whole-frame trace into `f`: its wall time kept if the best so far, and if `keep` its
/// 8-bit colours and rays (only those: a 1080p frame of records is ~0.6 GB).
void traceInto(const FrameTracer& tracer, Frame& f, bool keep)
{
  const int H = tracer.description().camera.height;
  const double t0 = now();
  const std::vector<RayRecord> records = tracer.traceRows(0, H);
  f.seconds = std::min(f.seconds, now() - t0);
  if (!keep)
    return;
  f.width = tracer.description().camera.width;
  f.height = H;
  f.rgb.resize(3 * records.size());
  f.rays = 0;
  for (std::size_t k = 0; k < records.size(); ++k)
  {
    f.rays += records[k].raysPerPixel;
    for (int c = 0; c < 3; ++c)
      f.rgb[3 * k + c] =
        static_cast<std::uint8_t>(std::lround(255.0 * std::clamp(records[k].color[c], 0.0, 1.0)));
  }
}

/// The view traced with each rendering, `repetitions` rounds in which the configurations take
/// turns (so that a change in the shared machine's load falls on all of them); each one's best
/// wall time counts.
std::vector<Frame> renderAll(const SceneDescription& base,
                             const std::vector<AntialiasOptions>& configs, int repetitions)
{
  std::vector<std::unique_ptr<FrameTracer>> tracers;
  for (const AntialiasOptions& o : configs)
  {
    SceneDescription d = base;
    d.rendering = o;
    validateRendering(d.rendering, static_cast<long long>(d.camera.width) * d.camera.height);
    tracers.push_back(std::make_unique<FrameTracer>(d));
  }
  std::vector<Frame> frames(configs.size());
  for (Frame& f : frames)
    f.seconds = 1e300;
  for (int rep = 0; rep < repetitions; ++rep)
    for (std::size_t c = 0; c < configs.size(); ++c)
    {
      if (repetitions > 1 || configs.size() > 1)
        std::fprintf(stderr, "  round %d: %s...\n", rep + 1, describe(configs[c]).c_str());
      traceInto(*tracers[c], frames[c], rep + 1 == repetitions);
    }
  return frames;
}

Frame render(const SceneDescription& base, const AntialiasOptions& rendering, int repetitions)
{
  return renderAll(base, { rendering }, repetitions).front();
}

RgbView view(const Frame& f)
{
  return { f.width, f.height, f.rgb.data() };
}

/// The fraction of pixels with any channel more than kOffBy levels from the reference's.
double offFraction(const Frame& a, const Frame& ref)
{
  long off = 0;
  const std::size_t n = a.rgb.size() / 3;
  for (std::size_t k = 0; k < n; ++k)
    for (int c = 0; c < 3; ++c)
      if (std::abs(int(a.rgb[3 * k + c]) - int(ref.rgb[3 * k + c])) > kOffBy)
      {
        ++off;
        break;
      }
  return static_cast<double>(off) / static_cast<double>(n);
}

/// The mean absolute difference of two frames over pixels and channels, in 8-bit levels.
double meanAbsDifference(const Frame& a, const Frame& b)
{
  double sum = 0;
  for (std::size_t k = 0; k < a.rgb.size(); ++k)
    sum += std::abs(int(a.rgb[k]) - int(b.rgb[k]));
  return sum / static_cast<double>(a.rgb.size());
}

struct Row
{
  AntialiasOptions options;
  double psnr = 0, off = 0, rays = 0, time = 0, seconds = 0; ///< rays, time: relative to `none`
  bool meets() const
  {
    return psnr >= kGoalPsnr && off <= kGoalOffFraction && rays <= kGoalCost && time <= kGoalCost;
  }
};

std::string goalText(const Row& r)
{
  if (r.meets())
    return "**yes**";
  std::vector<std::string> missed;
  if (r.psnr < kGoalPsnr)
    missed.push_back("PSNR");
  if (r.off > kGoalOffFraction)
    missed.push_back("off");
  if (r.rays > kGoalCost)
    missed.push_back("rays");
  if (r.time > kGoalCost)
    missed.push_back("time");
  std::string s = "no (";
  for (std::size_t k = 0; k < missed.size(); ++k)
    s += (k ? ", " : "") + missed[k];
  return s + ")";
}

/// A PSNR for the tables: identical images have an infinite one.
std::string db(double x)
{
  if (std::isinf(x))
    return "∞";
  char b[32];
  std::snprintf(b, sizeof b, "%.1f", x);
  return b;
}

std::string seconds(double s)
{
  char b[32];
  if (s >= 1.0)
    std::snprintf(b, sizeof b, "%.2f s", s);
  else
    std::snprintf(b, sizeof b, "%.0f ms", 1e3 * s);
  return b;
}

/// The scene at the given size: its own camera and objects, nothing else changed.
SceneDescription resized(const SceneDescription& base, int w, int h)
{
  SceneDescription d = base;
  d.camera.width = w;
  d.camera.height = h;
  return d;
}

struct Table
{
  std::string file;
  std::vector<Row> rows;
};

/// One scene at one size: the reference, then every configuration (the first `none`, the costs'
/// unit), each against the reference. Prints the table and returns its rows.
Table sceneTable(const SceneDescription& scene, const std::string& file,
                 const std::vector<AntialiasOptions>& configs, int referenceSide, int repetitions)
{
  const int W = scene.camera.width, H = scene.camera.height;
  std::fprintf(stderr, "%s at %dx%d: reference (%dx%d rays a pixel)...\n", file.c_str(), W, H,
               referenceSide, referenceSide);
  const Frame ref = render(scene, options(AntialiasMode::None, 16, referenceSide), 1);
  Table t;
  t.file = file;
  const std::vector<Frame> frames = renderAll(scene, configs, repetitions);
  for (std::size_t c = 0; c < configs.size(); ++c)
  {
    const Frame& f = frames[c];
    Row r;
    r.options = configs[c];
    r.psnr = psnr(view(f), view(ref));
    r.off = offFraction(f, ref);
    r.seconds = f.seconds;
    r.rays = f.rays;
    r.time = f.seconds;
    t.rows.push_back(r);
  }
  const double noneRays = t.rows.front().rays, noneTime = t.rows.front().seconds;
  std::printf("\n#### `%s` at %d×%d\n\n", file.c_str(), W, H);
  std::printf("%s. Reference: %d×%d point samples a pixel, %s; `none`: %s a frame.\n\n",
              scene.name.c_str(), referenceSide, referenceSide, seconds(ref.seconds).c_str(),
              seconds(noneTime).c_str());
  std::printf("| configuration | PSNR (dB) | off by > %d | rays (× none) | wall time (× none) | "
              "wall time | meets the goal |\n|---|---|---|---|---|---|---|\n",
              kOffBy);
  for (Row& r : t.rows)
  {
    r.rays /= noneRays;
    r.time /= noneTime;
    std::printf("| %s | %s | %.2f %% | %.2f | %.2f | %s | %s |\n", describe(r.options).c_str(),
                db(r.psnr).c_str(), 100 * r.off, r.rays, r.time, seconds(r.seconds).c_str(),
                goalText(r).c_str());
  }
  std::fflush(stdout);
  return t;
}

/// Every configuration over all scenes of one size: how many meet the goal, the worst of each.
void summary(const std::vector<Table>& tables)
{
  if (tables.size() < 2)
    return;
  std::printf("\n#### All scenes at this size\n\n"
              "Worst case over the %zu scenes (lowest PSNR, most pixels off, highest costs) and "
              "the mean PSNR.\n\n"
              "| configuration | meets the goal | worst PSNR (dB) | mean PSNR (dB) | most off by "
              "> %d | most rays (× none) | longest wall time (× none) |\n"
              "|---|---|---|---|---|---|---|\n",
              tables.size(), kOffBy);
  for (std::size_t c = 0; c < tables.front().rows.size(); ++c)
  {
    int meets = 0;
    double worst = std::numeric_limits<double>::infinity(), mean = 0, off = 0, rays = 0, time = 0;
    for (const Table& t : tables)
    {
      const Row& r = t.rows[c];
      meets += r.meets();
      worst = std::min(worst, r.psnr);
      mean += r.psnr / static_cast<double>(tables.size());
      off = std::max(off, r.off);
      rays = std::max(rays, r.rays);
      time = std::max(time, r.time);
    }
    std::printf("| %s | %d of %zu | %s | %s | %.2f %% | %.2f | %.2f |\n",
                describe(tables.front().rows[c].options).c_str(), meets, tables.size(),
                db(worst).c_str(), db(mean).c_str(), 100 * off, rays, time);
  }
}

/// The 200×200 points for bench/plot-antialias: one line a scene and configuration.
void writePlotData(const char* path, const std::vector<Table>& tables)
{
  FILE* f = std::fopen(path, "w");
  if (!f)
  {
    std::fprintf(stderr, "cannot write %s\n", path);
    return;
  }
  std::fprintf(f,
               "scene\tconfiguration\tmode\tcap\tsupersample\tthreshold\trays\ttime\tpsnr\toff\n");
  for (const Table& t : tables)
    for (const Row& r : t.rows)
      std::fprintf(f, "%s\t%s\t%s\t%d\t%d\t%g\t%.4f\t%.4f\t%.3f\t%.6f\n", t.file.c_str(),
                   describe(r.options).c_str(), toString(r.options.mode), r.options.maxRaysPerPixel,
                   r.options.supersample, r.options.colorThreshold, r.rays, r.time, r.psnr, r.off);
  std::fclose(f);
}

struct Movie
{
  AntialiasOptions options;
  std::vector<Frame> frames;
  double seconds = 0, rays = 0; ///< over the whole movie
};

/// The scene's camera turned about z through the frames of an orbit over `degrees`, each frame
/// traced once with every rendering in turn (the load of the shared machine falls on all alike).
std::vector<Movie> orbit(const SceneDescription& scene,
                         const std::vector<AntialiasOptions>& configs, int frames, double degrees)
{
  std::vector<Movie> movies(configs.size());
  for (std::size_t c = 0; c < configs.size(); ++c)
    movies[c].options = configs[c];
  const tools::CameraPose pose{ scene.camera.position, scene.camera.focalPoint,
                                scene.camera.viewUp };
  for (int k = 0; k < frames; ++k)
  {
    std::fprintf(stderr, "orbit: frame %d of %d\n", k + 1, frames);
    const tools::CameraPose p = tools::turnedAboutZ(pose, tools::orbitAngle(k, frames, degrees));
    SceneDescription d = scene;
    d.camera.position = p.position;
    d.camera.focalPoint = p.focalPoint;
    d.camera.viewUp = p.viewUp;
    std::vector<Frame> traced = renderAll(d, configs, 1);
    for (std::size_t c = 0; c < configs.size(); ++c)
    {
      movies[c].seconds += traced[c].seconds;
      movies[c].rays += traced[c].rays;
      movies[c].frames.push_back(std::move(traced[c]));
    }
  }
  return movies;
}

/// Mean over consecutive frames of their mean absolute difference (8-bit levels).
double flicker(const Movie& m)
{
  double sum = 0;
  for (std::size_t k = 1; k < m.frames.size(); ++k)
    sum += meanAbsDifference(m.frames[k], m.frames[k - 1]);
  return sum / static_cast<double>(m.frames.size() - 1);
}

/// Mean over consecutive frames of the mean absolute difference between the movie's change from
/// one frame to the next and the reference's: the change that is not the scene's motion.
double flickerError(const Movie& m, const Movie& ref)
{
  double sum = 0;
  for (std::size_t k = 1; k < m.frames.size(); ++k)
  {
    const auto &a = m.frames[k].rgb, &a0 = m.frames[k - 1].rgb;
    const auto &b = ref.frames[k].rgb, &b0 = ref.frames[k - 1].rgb;
    double s = 0;
    for (std::size_t q = 0; q < a.size(); ++q)
      s += std::abs((int(a[q]) - int(a0[q])) - (int(b[q]) - int(b0[q])));
    sum += s / static_cast<double>(a.size());
  }
  return sum / static_cast<double>(m.frames.size() - 1);
}

/// The orbit of Fig. 1: flicker of each configuration's movie against the reference movie's.
void orbitSection(const SceneDescription& scene, const std::string& file, int frames,
                  int referenceSide)
{
  const double degrees = 90.0;
  std::vector<AntialiasOptions> configs = { options(AntialiasMode::None) };
  for (const char* preset : { "fast", "balanced", "accurate" })
    if (std::find(configs.begin(), configs.end(), renderingPreset(preset)) == configs.end())
      configs.push_back(renderingPreset(preset));
  configs.push_back(options(AntialiasMode::None, 16, referenceSide));
  std::vector<Movie> movies = orbit(scene, configs, frames, degrees);
  const Movie ref = movies.back();
  movies.pop_back();
  const double refFlicker = flicker(ref);
  const Movie& none = movies.front();
  std::printf(
    "\n### Temporal flicker: a %.0f° camera orbit of Fig. 1 at %d×%d\n\n"
    "`%s`, the camera turned about the z axis through the origin (`tools::turnedAboutZ`: same "
    "distance and height, looking at the origin) in %d frames %.0f° apart, each frame traced "
    "on its own. *Flicker*: the mean absolute difference between consecutive frames, over "
    "pixels and channels, in 8-bit levels, averaged over the %d pairs; the reference movie "
    "(%d×%d point samples a pixel, %s in all) has %.2f, the scene's own motion. *Excess "
    "change*: the mean absolute difference between a movie's frame-to-frame change and the "
    "reference's (what is not the motion). Goal: flicker within %.0f %% of the reference's.\n\n"
    "| configuration | flicker (levels) | against the reference | excess change (levels) | mean "
    "PSNR (dB) | rays (× none) | wall time (× none) | meets the goal |\n"
    "|---|---|---|---|---|---|---|---|\n",
    degrees, scene.camera.width, scene.camera.height, file.c_str(), frames, degrees / (frames - 1),
    frames - 1, referenceSide, referenceSide, seconds(ref.seconds).c_str(), refFlicker,
    100 * kGoalFlicker);
  for (const Movie& m : movies)
  {
    double meanPsnr = 0;
    for (std::size_t k = 0; k < m.frames.size(); ++k)
      meanPsnr +=
        psnr(view(m.frames[k]), view(ref.frames[k])) / static_cast<double>(m.frames.size());
    const double f = flicker(m), rel = f / refFlicker - 1.0;
    std::printf("| %s | %.2f | %+.1f %% | %.2f | %s | %.2f | %.2f | %s |\n",
                describe(m.options).c_str(), f, 100 * rel, flickerError(m, ref),
                db(meanPsnr).c_str(), m.rays / none.rays, m.seconds / none.seconds,
                std::abs(rel) <= kGoalFlicker ? "**yes**" : "no");
  }
  std::printf("| reference | %.2f | — | 0 | ∞ | %.2f | %.2f | — |\n", refFlicker,
              ref.rays / none.rays, ref.seconds / none.seconds);
  std::fflush(stdout);
}

bool parseSize(const char* s, int& w, int& h)
{
  return std::sscanf(s, "%dx%d", &w, &h) == 2 && w > 0 && h > 0;
}

std::vector<AntialiasOptions> smallConfigs()
{
  std::vector<AntialiasOptions> c = { options(AntialiasMode::None),
                                      options(AntialiasMode::Filter) };
  for (int cap : { 5, 9, 17, 25, 49 })
    c.push_back(options(AntialiasMode::Adaptive, cap));
  for (double threshold : { 0.25, 0.1 })
    c.push_back(options(AntialiasMode::Adaptive, 9, 1, threshold));
  for (int n : { 2, 3 })
    c.push_back(options(AntialiasMode::Filter, 16, n));
  return c;
}

std::vector<AntialiasOptions> hdConfigs()
{
  std::vector<AntialiasOptions> c = { options(AntialiasMode::None),
                                      options(AntialiasMode::Filter) };
  for (int cap : { 9, 17 })
    c.push_back(options(AntialiasMode::Adaptive, cap));
  return c;
}

void printSetUp(const std::string& command, int small[2], int hd[2], int repetitions)
{
  const std::string commit = commandOutput("git rev-parse --short HEAD 2>/dev/null");
  const std::string dirty = commandOutput("git status --porcelain -- Module Filters 2>/dev/null");
  std::printf(
    "- **Machine:** %s; %d OpenMP threads, load average %.1f when the run started (the cores "
    "are shared with other work: costs relative to `none` in the same run are what count).\n"
    "- **Core measured:** commit `%s`%s.\n"
    "- **Regenerate:** `bench/run` (`ASRT_BENCH_ONLY=antialias`). It ran, from the repository "
    "root:\n\n  ```\n  %s\n  ```\n\n",
    machine().c_str(), omp_get_max_threads(), loadAverage(),
    commit.empty() ? "?" : commit.substr(0, commit.find('\n')).c_str(),
    dirty.empty() ? "" : " with local changes", command.c_str());
  std::printf(
    "### Set-up\n\n"
    "- A pixel's true colour is the box-filtered average of the picture over its unit square "
    "(`Antialiasing.h`). The **reference** of a view is that average estimated by N×N point "
    "samples on the rotated grid that adaptive sampling uses (`supersample` N, mode `none`; one "
    "sample in each of the N×N cells and in each of the N² rows and columns of the pixel): N = %d "
    "(%d samples a pixel) at %d×%d, N = %d (%d samples) at %d×%d, traced in the same run.\n"
    "- `none`: one ray through the pixel's centre, textures point-sampled (the cost unit). "
    "`filter`: the same ray, its texture lookup averaged over the pixel's footprint. "
    "`adaptive`, cap n: `filter`, and a pixel takes the k×k pattern (k the largest whose rays fit "
    "in n: k² for odd k, k² + 1 for even k, whose pattern does not hold the centre ray) where its "
    "footprint is undefined or misplaces an edge neighbour by half a pixel or more, or (with a "
    "colour threshold below 1) a channel differs by more, or where an edge neighbour's centre ray "
    "ends differently (object, image order, ending) and so does the ray through the midpoint "
    "between the two centres. Each sample is filtered over its share of the footprint. "
    "`filter, supersample` N: every pixel N×N filtered samples.\n"
    "- **Rays**: the sum over the frame's pixels of `RayRecord::raysPerPixel` (every ray traced: "
    "the centre ray, the pattern's, and the midpoint rays, each counted once), relative to "
    "`none`'s (one a pixel). **Wall time**: the best "
    "of %d whole-frame traces (`FrameTracer::traceRows`: centre rays, Jacobians, anti-aliasing; no "
    "output), "
    "relative to `none`'s best in the same run (at 1920×1080 one trace each).\n"
    "- **PSNR**: 10 log10(255² / MSE) over the three channels (`asrt::psnr`) of the colours "
    "quantised as the PNG stores them, round(255 · clamp(c, 0, 1)), the reference's too. **Off "
    "by > %d**: the pixels with any channel more than %d/255 from the reference's.\n"
    "- **Goal**: PSNR ≥ %.0f dB, at most %.1f %% of pixels off by > %d, at most %.0f× the rays and "
    "the wall time of `none`.\n",
    8, 64, small[0], small[1], 4, 16, hd[0], hd[1], repetitions, kOffBy, kOffBy, kGoalPsnr,
    100 * kGoalOffFraction, kOffBy, kGoalCost);
}
}

int main(int argc, char* argv[])
{
  std::vector<std::string> files;
  bool runHd = true;
  int small[2] = { 200, 200 }, hd[2] = { 1920, 1080 }, orbitFrames = 16, repetitions = 3;
  const char* plotData = nullptr;
  std::string command = argv[0];
  for (int k = 1; k < argc; ++k)
  {
    command += std::string(" ") + argv[k];
    const std::string a = argv[k];
    const bool more = k + 1 < argc;
    if (a == "--no-hd")
      runHd = false;
    else if (a == "--small" && more && parseSize(argv[k + 1], small[0], small[1]))
      command += std::string(" ") + argv[++k];
    else if (a == "--hd" && more && parseSize(argv[k + 1], hd[0], hd[1]))
      command += std::string(" ") + argv[++k];
    else if (a == "--orbit-frames" && more && (orbitFrames = std::atoi(argv[k + 1])) >= 2)
      command += std::string(" ") + argv[++k];
    else if (a == "--repetitions" && more && (repetitions = std::atoi(argv[k + 1])) >= 1)
      command += std::string(" ") + argv[++k];
    else if (a == "--plot-data" && more)
      command += std::string(" ") + (plotData = argv[++k]);
    else if (!a.empty() && a[0] != '-')
      files.push_back(a);
    else
    {
      std::fprintf(stderr,
                   "usage: %s scene.json... [--no-hd] [--small WxH] [--hd WxH] "
                   "[--orbit-frames N>=2] [--repetitions N>=1] [--plot-data FILE]\n",
                   argv[0]);
      return 2;
    }
  }
  if (files.empty())
  {
    std::fprintf(stderr, "%s: no scene files given\n", argv[0]);
    return 2;
  }
  if (const char* only = std::getenv("ASRT_BENCH_AA_ONLY"))
    command = std::string("ASRT_BENCH_AA_ONLY=") + only + " " + command;

  const double start = now();
  std::printf("<!-- antialias:begin -->\n## Anti-aliasing: quality against cost\n\n");
  printSetUp(command, small, hd, repetitions);
  std::vector<SceneDescription> scenes;
  for (const std::string& f : files)
    scenes.push_back(loadSceneFile(f, vtkImageFileLoader()));

  std::printf("\n### Every scene at %d×%d\n", small[0], small[1]);
  std::vector<Table> tables;
  for (std::size_t s = 0; s < files.size(); ++s)
    if (wanted(files[s]))
      tables.push_back(sceneTable(resized(scenes[s], small[0], small[1]), files[s], smallConfigs(),
                                  8, repetitions));
  summary(tables);
  if (plotData && !tables.empty())
  {
    writePlotData(plotData, tables);
    std::printf("\n![PSNR against rays per pixel, every scene at %d×%d](antialias-tradeoff.png)\n",
                small[0], small[1]);
  }
  const double smallSeconds = now() - start;

  double orbitSeconds = 0;
  for (std::size_t s = 0; s < files.size(); ++s)
    if (files[s].find("fig1") != std::string::npos && wanted("orbit"))
    {
      const double t0 = now();
      orbitSection(resized(scenes[s], small[0], small[1]), files[s], orbitFrames, 8);
      orbitSeconds = now() - t0;
      break;
    }

  double hdSeconds = 0;
  if (runHd)
  {
    const double t0 = now();
    std::printf("\n### At %d×%d\n", hd[0], hd[1]);
    for (std::size_t s = 0; s < files.size(); ++s)
      if (wanted(files[s]))
        sceneTable(resized(scenes[s], hd[0], hd[1]), files[s], hdConfigs(), 4, 1);
    hdSeconds = now() - t0;
  }
  std::printf("\nThe run took %.0f s: %.0f s at %d×%d, %.0f s for the orbit%s.\n", now() - start,
              smallSeconds, small[0], small[1], orbitSeconds,
              runHd ? (", " + std::to_string(std::lround(hdSeconds)) + " s at " +
                       std::to_string(hd[0]) + "×" + std::to_string(hd[1]))
                        .c_str()
                    : " (the 1920×1080 part not run: `--no-hd`)");
  std::printf("<!-- antialias:end -->\n");
  return 0;
}
