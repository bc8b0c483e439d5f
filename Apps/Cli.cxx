#include "Cli.h"

#include "AdaptiveGrid.h"
#include "DataFiles.h"
#include "InterruptibleRead.h"
#include "Progress.h"
#include "Propagator.h"
#include "RayRecord.h"
#include "RayStore.h"
#include "SceneFile.h"
#include "StoreConnection.h"
#include "VtkMessages.h"
#include "vtkGeodesicPostgreSQLReader.h"
#include "vtkGeodesicSource.h"
#include "vtkImageData.h"

#include <vtksys/SystemTools.hxx>

#include <dirent.h>
#include <sys/stat.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <limits>

namespace asrt
{
namespace cli
{
const char* const kExitCodeHelp = R"(Exit codes:
  0    success
  1    the work failed (a file could not be written, more rays failed than
       --max-failed-share allows, rendering failed, ...)
  2    usage error (unknown option, missing or malformed value)
  3    database error (unreachable, refused, a table locked past ASRT_LOCK_TIMEOUT,
       no such frame, frame already stored)
  4    bad input (scene file, texture, parameters: e.g. camera inside the horizon)
  130  interrupted with Ctrl-C (nothing half-written is left behind)
)";

const char* const kSceneOverrideHelp = R"(Scene overrides (the scene file's values otherwise):
  --mass M              the hole's mass (0: flat space)
  --spin A              Kerr spin a, |a| <= M
  --charge Q            Reissner-Nordstrom charge, |Q| <= M
  --camera X,Y,Z        the eye (in M, Kerr-Schild chart, the hole at the origin)
  --focal X,Y,Z         the point looked at
  --view-up X,Y,Z       the camera's up direction
  --view-angle DEG      vertical field of view, in degrees
  -r, --resolution WxH  image size in pixels, e.g. 200x200
  --preset NAME         fast, balanced or accurate (rtol 1e-8, 1e-10, 1e-12 for the
                        method auto picks; fast and balanced on the adaptive grid,
                        accurate tracing every pixel; measured in bench/REPORT.md)
  --method NAME         an integrator ("asrt bench" and bench/REPORT.md compare them)
  --antialias MODE      none (one ray a pixel), filter (textures filtered over each
                        pixel's footprint) or adaptive (filter, and up to --max-rays rays
                        in pixels whose neighbours disagree); the preset's otherwise
  --max-rays N          the most rays an adaptively sampled pixel takes (1 to 1024)
  --supersample N       N x N rays in every pixel (1 to 32), for reference pictures
  --grid N              trace every Nth pixel's ray (1 to 256) and refine where rays
                        disagree, interpolating the rest (default 8, the fast and
                        balanced presets' too; 1 traces every pixel, as the accurate
                        preset does; a supersample always does)
  --grid-tolerance T    the largest error of the interpolated surface (u, v) that leaves a
                        grid block unrefined (default 3e-4)
  --step H              the integrator's step
  --max-failed-share F  refuse the frame (exit 1, nothing written or stored) when more than
                        this fraction of its rays failed numerically or ran out of steps
                        (default 0.05; 1 accepts any frame)
)";

const char* const kDatabaseHelp = R"(Database:
  --db CONNINFO         libpq connection string or URI, e.g. "host=/tmp dbname=asrt"; else
                        $ASRT_DB, else the standard PG* variables if any is set, else the
                        private server of "asrt db" (started when needed)
  ASRT_LOCK_TIMEOUT     seconds a read waits for a table that another session holds locked
                        before it gives up naming the table (exit code 3); default 30, 0
                        waits as long as the lock is held. Ctrl-C stops any wait at once.
)";

std::vector<OptionSpec> operator+(std::vector<OptionSpec> a, const std::vector<OptionSpec>& b)
{
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

Options::Options(const std::vector<OptionSpec>& specs, const std::vector<std::string>& args)
{
  bool optionsEnded = false;
  for (std::size_t k = 0; k < args.size(); ++k)
  {
    const std::string& arg = args[k];
    if (optionsEnded || arg.size() < 2 || arg[0] != '-' ||
        (arg[1] != '-' && !std::isalpha(static_cast<unsigned char>(arg[1]))))
    {
      this->Positional.push_back(arg); // includes negative numbers such as -3
      continue;
    }
    if (arg == "--")
    {
      optionsEnded = true;
      continue;
    }
    if (arg == "-h" || arg == "--help")
    {
      this->Help = true;
      continue;
    }
    std::string name, value;
    bool hasValue = false;
    const OptionSpec* spec = nullptr;
    if (arg[1] == '-')
    {
      const std::size_t eq = arg.find('=');
      name = arg.substr(2, eq == std::string::npos ? std::string::npos : eq - 2);
      if (eq != std::string::npos)
      {
        value = arg.substr(eq + 1);
        hasValue = true;
      }
      for (const OptionSpec& s : specs)
        if (s.name == name)
          spec = &s;
    }
    else
    {
      if (arg.size() != 2)
        throw UsageError("unknown option " + quotedArgument(arg));
      for (const OptionSpec& s : specs)
        if (s.shortName == arg[1])
          spec = &s;
      if (spec)
        name = spec->name;
    }
    if (!spec)
      throw UsageError("unknown option " + quotedArgument(arg));
    switch (spec->kind)
    {
      case OptionSpec::Flag:
        if (hasValue)
          throw UsageError("--" + name + " takes no value");
        break;
      case OptionSpec::Value:
        if (!hasValue)
        {
          if (k + 1 >= args.size())
            throw UsageError("--" + name + " needs a value");
          value = args[++k];
        }
        break;
      case OptionSpec::OptionalValue:
        break;
    }
    this->Values[name] = value;
  }
}

std::string Options::get(const std::string& name, const std::string& fallback) const
{
  auto it = this->Values.find(name);
  return it == this->Values.end() ? fallback : it->second;
}

void Options::expectPositional(std::size_t min, std::size_t max, const char* what) const
{
  const std::size_t n = this->Positional.size();
  if (n < min)
    throw UsageError(std::string("missing ") + what);
  if (n > max)
    throw UsageError("unexpected argument " + quotedArgument(this->Positional[max]));
}

std::string quotedArgument(const std::string& text)
{
  if (text.size() <= kQuotedLength)
    return "'" + text + "'";
  std::size_t cut = kQuotedLength - 3;
  while (cut > 0 && (static_cast<unsigned char>(text[cut]) & 0xC0) == 0x80)
    --cut; // not inside a UTF-8 character
  return "'" + text.substr(0, cut) + "...' (" + std::to_string(text.size()) + " characters)";
}

std::vector<bool> parseFormatList(const std::string& list, const std::vector<std::string>& known)
{
  std::string names;
  for (const std::string& k : known)
    names += (names.empty() ? "" : ", ") + k;
  std::vector<bool> chosen(known.size(), false);
  std::size_t from = 0;
  while (from <= list.size())
  {
    const std::size_t comma = std::min(list.find(',', from), list.size());
    const std::string item = list.substr(from, comma - from);
    from = comma + 1;
    if (item.empty())
      continue;
    const auto at = std::find(known.begin(), known.end(), item);
    if (at == known.end())
      throw UsageError("--formats: unknown format " + quotedArgument(item) + " (" + names + ")");
    chosen[static_cast<std::size_t>(at - known.begin())] = true;
  }
  if (std::find(chosen.begin(), chosen.end(), true) == chosen.end())
    throw UsageError("--formats: the list is empty; name one or more of " + names);
  return chosen;
}

double parseNumber(const std::string& option, const std::string& text)
{
  char* end = nullptr;
  errno = 0;
  const double v = std::strtod(text.c_str(), &end);
  if (text.empty() || end != text.c_str() + text.size())
    throw UsageError(option + ": " + quotedArgument(text) + " is not a number");
  if (!std::isfinite(v))
    throw UsageError(option + ": must be finite, got " + quotedArgument(text));
  // strtod reports ERANGE for results beyond a double's range and for those that underflow to
  // zero or to a subnormal number (which keeps too few digits to be the number typed).
  if (errno == ERANGE)
    throw UsageError(option + ": " + quotedArgument(text) +
                     " is out of a double's range (it would read as " + asrt::exactNumber(v) + ")");
  return v;
}

int parsePositiveInteger(const std::string& option, const std::string& text)
{
  char* end = nullptr;
  const long v = std::strtol(text.c_str(), &end, 10);
  if (text.empty() || end != text.c_str() + text.size() || v < 1 || v > 1000000000)
    throw UsageError(option + ": " + quotedArgument(text) + " is not a positive integer");
  return static_cast<int>(v);
}

std::vector<double> parseNumbers(const std::string& option, const std::string& text,
                                 std::size_t count, char separator)
{
  std::vector<double> values;
  std::size_t begin = 0;
  while (true)
  {
    const std::size_t end = text.find(separator, begin);
    values.push_back(parseNumber(option, text.substr(begin, end - begin)));
    if (end == std::string::npos)
      break;
    begin = end + 1;
  }
  if (values.size() != count)
    throw UsageError(option + ": expected " + std::to_string(count) + " numbers separated by '" +
                     separator + "', got " + quotedArgument(text));
  return values;
}

std::pair<int, int> parseSize(const std::string& option, const std::string& text)
{
  const std::size_t x = text.find_first_of("xX");
  if (x == std::string::npos)
    throw UsageError(option + ": expected WIDTHxHEIGHT, e.g. 200x200, got " + quotedArgument(text));
  const int w = parsePositiveInteger(option, text.substr(0, x));
  const int h = parsePositiveInteger(option, text.substr(x + 1));
  // The pixel budget of a scene file's frames, for every size given here.
  if (static_cast<long long>(w) * h > kMaxFramePixels)
    throw UsageError(option + ": " + text + " is more than the " + std::to_string(kMaxFramePixels) +
                     " pixels (2^28) allowed");
  return { w, h };
}

std::optional<double> Options::number(const std::string& name) const
{
  if (!this->has(name))
    return std::nullopt;
  return parseNumber("--" + name, this->get(name));
}

std::optional<int> Options::positiveInteger(const std::string& name) const
{
  if (!this->has(name))
    return std::nullopt;
  return parsePositiveInteger("--" + name, this->get(name));
}

std::optional<std::vector<double>> Options::vector3(const std::string& name) const
{
  if (!this->has(name))
    return std::nullopt;
  return parseNumbers("--" + name, this->get(name), 3, ',');
}

std::optional<std::pair<int, int>> Options::size(const std::string& name) const
{
  if (!this->has(name))
    return std::nullopt;
  return parseSize("--" + name, this->get(name));
}

const std::vector<OptionSpec>& sceneOverrideSpecs()
{
  static const std::vector<OptionSpec> specs = {
    { "mass", OptionSpec::Value },          { "spin", OptionSpec::Value },
    { "charge", OptionSpec::Value },        { "camera", OptionSpec::Value },
    { "focal", OptionSpec::Value },         { "view-up", OptionSpec::Value },
    { "view-angle", OptionSpec::Value },    { "resolution", OptionSpec::Value, 'r' },
    { "preset", OptionSpec::Value },        { "method", OptionSpec::Value },
    { "step", OptionSpec::Value },          { "max-failed-share", OptionSpec::Value },
    { "antialias", OptionSpec::Value },     { "max-rays", OptionSpec::Value },
    { "supersample", OptionSpec::Value },   { "grid", OptionSpec::Value },
    { "grid-tolerance", OptionSpec::Value }
  };
  return specs;
}

void applySceneOverrides(const Options& options, vtkGeodesicSource* source)
{
  if (auto m = options.number("mass"))
    source->SetMass(*m);
  if (auto a = options.number("spin"))
    source->SetSpin(*a);
  if (auto q = options.number("charge"))
    source->SetCharge(*q);
  if (auto p = options.vector3("camera"))
    source->SetCameraPosition(p->data());
  if (auto f = options.vector3("focal"))
    source->SetFocalPoint(f->data());
  if (auto u = options.vector3("view-up"))
    source->SetViewUp(u->data());
  if (auto angle = options.number("view-angle"))
    source->SetViewAngle(*angle);
  if (auto wh = options.size("resolution"))
    source->SetResolution(wh->first, wh->second);
  if (options.has("preset"))
  {
    const std::string preset = options.get("preset");
    try
    {
      asrt::integratorPreset(preset);
    }
    catch (const std::exception& e)
    {
      throw UsageError("--preset: " + std::string(e.what()));
    }
    source->SetIntegrationPreset(preset.c_str());
  }
  if (options.has("method"))
  {
    const std::string method = options.get("method");
    if (method != "auto")
    {
      try
      {
        asrt::findMethod(method);
      }
      catch (const std::exception& e)
      {
        throw UsageError("--method: " + std::string(e.what()));
      }
    }
    source->SetIntegrationMethod(method.c_str());
  }
  if (auto h = options.number("step"))
  {
    if (!(*h > 0.0))
      throw UsageError("--step: must be positive");
    source->SetIntegrationStep(*h);
  }
  if (options.has("antialias"))
  {
    const std::string mode = options.get("antialias");
    try
    {
      asrt::antialiasModeFromString(mode);
    }
    catch (const std::exception& e)
    {
      throw UsageError("--antialias: " + std::string(e.what()));
    }
    source->SetAntialias(mode.c_str());
  }
  if (auto n = options.positiveInteger("max-rays"))
  {
    if (*n > asrt::kMaxRaysPerPixel)
      throw UsageError("--max-rays: must lie in [1, " + std::to_string(asrt::kMaxRaysPerPixel) +
                       "], got " + std::to_string(*n));
    source->SetMaxRaysPerPixel(*n);
  }
  if (auto n = options.positiveInteger("supersample"))
  {
    if (*n > 32)
      throw UsageError("--supersample: must lie in [1, 32], got " + std::to_string(*n));
    source->SetSupersample(*n);
  }
  if (auto n = options.positiveInteger("grid"))
  {
    if (*n > asrt::kMaxGridLattice)
      throw UsageError("--grid: must lie in [1, " + std::to_string(asrt::kMaxGridLattice) +
                       "], got " + std::to_string(*n));
    source->SetGridLattice(*n);
  }
  if (auto t = options.number("grid-tolerance"))
  {
    if (!(*t >= 0.0) || !std::isfinite(*t))
      throw UsageError("--grid-tolerance: must be finite and at least 0, got " +
                       quotedArgument(options.get("grid-tolerance")));
    source->SetGridTolerance(*t);
  }
  maxFailedShare(options); // a malformed value is refused before anything is traced
}

double maxFailedShare(const Options& options)
{
  const std::optional<double> share = options.number("max-failed-share");
  if (share && !(*share >= 0.0 && *share <= 1.0))
    throw UsageError("--max-failed-share: must be a fraction in [0, 1], got " +
                     quotedArgument(options.get("max-failed-share")));
  return share.value_or(kDefaultMaxFailedShare);
}

namespace
{
std::string percent(double fraction)
{
  char text[32];
  std::snprintf(text, sizeof text, "%.3g %%", 100.0 * fraction);
  return text;
}
}

namespace
{
void checkRayEnds(long long traced, long long failed, long long outOfSteps, double maxShare,
                  const std::string& label)
{
  const double share = traced > 0 ? static_cast<double>(failed + outOfSteps) / traced : 0.0;
  std::printf("%s: %lld rays, %lld failed numerically, %lld out of steps (%s; at most %s "
              "allowed)\n",
              label.c_str(), traced, failed, outOfSteps, percent(share).c_str(),
              percent(maxShare).c_str());
  std::fflush(stdout);
  if (share > maxShare)
    throw std::runtime_error(
      label + ": the failed share is " + percent(share) + " (" + std::to_string(failed) + " of " +
      std::to_string(traced) + " rays failed numerically, " + std::to_string(outOfSteps) +
      " ran out of steps), above the " + percent(maxShare) +
      " --max-failed-share allows: the frame is refused, nothing of it written or stored. A "
      "smaller --step, another --method or a larger tracing.maxSteps may help; "
      "--max-failed-share 1 accepts the frame as it is");
}
}

void checkRayEnds(vtkImageData* frame, double maxShare, const std::string& label)
{
  vtkIdType counts[3];
  if (!vtkGeodesicSource::CountRayEnds(frame, counts))
    throw std::runtime_error(label + ": the traced frame has no Termination array to check");
  checkRayEnds(counts[0], counts[1], counts[2], maxShare, label);
}

void checkRayEnds(const std::vector<RayRecord>& frame, double maxShare, const std::string& label)
{
  long long traced = 0, failed = 0, outOfSteps = 0;
  for (const RayRecord& r : frame)
  {
    if (r.termination == Termination::Running)
      continue; // not traced
    ++traced;
    failed += r.termination == Termination::NumericalFailure;
    outOfSteps += r.termination == Termination::StepBudget;
  }
  checkRayEnds(traced, failed, outOfSteps, maxShare, label);
}

const std::vector<OptionSpec>& databaseSpecs()
{
  static const std::vector<OptionSpec> specs = { { "db", OptionSpec::Value } };
  return specs;
}

std::string databaseGiven(const Options& options)
{
  std::string given = options.get("db");
  if (given.empty())
    if (const char* env = std::getenv("ASRT_DB"))
      given = env;
  return given;
}

std::string databaseConnection(const Options& options)
{
  try
  {
    return asrt::storeConnection(databaseGiven(options).c_str());
  }
  catch (const std::exception& e)
  {
    throw DatabaseError(std::string("cannot start the private PostgreSQL server: ") + e.what());
  }
}

std::chrono::milliseconds readLockTimeout()
{
  const char* text = std::getenv("ASRT_LOCK_TIMEOUT");
  if (!text || !*text)
    return RayStore::kDefaultReadLockTimeout;
  const double seconds = parseNumber("ASRT_LOCK_TIMEOUT", text);
  // PostgreSQL's lock_timeout counts milliseconds in an int.
  constexpr double kMaxSeconds = 2147483;
  if (seconds < 0 || seconds > kMaxSeconds)
    throw UsageError("ASRT_LOCK_TIMEOUT: " + quotedArgument(text) +
                     " is not a number of seconds from 0 to 2147483");
  // Whole milliseconds; a positive time never becomes 0, which would mean no limit at all.
  return std::chrono::milliseconds(std::max(std::llround(seconds * 1000), seconds > 0 ? 1LL : 0LL));
}

void limitReads(RayStore& store)
{
  store.setReadLockTimeout(readLockTimeout());
  store.setReadCancellation(&tools::interruptRequested);
}

void limitReads(vtkGeodesicPostgreSQLReader* reader)
{
  reader->SetLockTimeout(double(readLockTimeout().count()) / 1000);
  reader->SetCancelRequested(&tools::interruptRequested);
}

std::int64_t parseFrameId(const std::string& text)
{
  // Digits only (strtoll would take a sign, spaces and "0x"), within the store's bigint ids.
  char* end = nullptr;
  errno = 0;
  const long long v = std::strtoll(text.c_str(), &end, 10);
  const bool digits = !text.empty() && std::all_of(text.begin(), text.end(),
                                                   [](char c) { return c >= '0' && c <= '9'; });
  if (!digits || end != text.c_str() + text.size() || errno == ERANGE || v < 1)
    throw UsageError(quotedArgument(text) + " is not a frame id (a positive integer up to " +
                     std::to_string(std::numeric_limits<std::int64_t>::max()) + "; see asrt list)");
  return static_cast<std::int64_t>(v);
}

std::string outputPath(const Options& options, const std::string& scenePath,
                       const std::string& suffix)
{
  namespace fs = vtksys;
  const std::string name = fs::SystemTools::GetFilenameWithoutLastExtension(scenePath) + suffix;
  std::string out = options.get("output");
  if (out.empty())
    out = name;
  else if (out.back() == '/' || fs::SystemTools::FileIsDirectory(out))
    out = (out.back() == '/' ? out : out + "/") + name;
  const std::string dir = fs::SystemTools::GetFilenamePath(out);
  if (!dir.empty() && !fs::SystemTools::MakeDirectory(dir).IsSuccess())
    throw std::runtime_error("cannot create the directory \"" + dir + "\"");
  return out;
}

std::string outputPrefix(const Options& options, const std::string& scenePath)
{
  const std::string prefix = outputPath(options, scenePath, "");
  struct stat st;
  // Followed: a link to /dev/null names /dev/null as much as the device's own name does.
  if (stat(prefix.c_str(), &st) == 0 && !S_ISREG(st.st_mode) && !S_ISDIR(st.st_mode))
    throw UsageError("--output: \"" + prefix + "\" is " +
                     (S_ISCHR(st.st_mode)    ? "a character device"
                      : S_ISFIFO(st.st_mode) ? "a FIFO"
                      : S_ISBLK(st.st_mode)  ? "a block device"
                      : S_ISSOCK(st.st_mode) ? "a socket"
                                             : "not a regular file") +
                     ": give a folder or a file-name prefix (the files are PREFIX.png, "
                     "PREFIX.vti, ...)");
  return prefix;
}

std::vector<std::string> staleFrames(const std::string& prefix, int count)
{
  const std::filesystem::path p(prefix);
  const std::string dir = p.parent_path().string();
  const std::string base = p.filename().string() + "-";
  std::vector<std::string> stale;
  DIR* listing = opendir(dir.empty() ? "." : dir.c_str());
  if (!listing)
    return stale;
  while (const dirent* entry = readdir(listing))
  {
    const std::string name = entry->d_name;
    const std::size_t dot = name.rfind('.');
    if (name.compare(0, base.size(), base) != 0 || dot == std::string::npos || dot <= base.size() ||
        (name.substr(dot) != ".png" && name.substr(dot) != ".vti"))
      continue;
    const std::string digits = name.substr(base.size(), dot - base.size());
    if (digits.size() > 9 || digits.find_first_not_of("0123456789") != std::string::npos)
      continue;
    const int number = std::stoi(digits);
    char canonical[32];
    std::snprintf(canonical, sizeof canonical, "%03d", number);
    const std::string path = (dir.empty() ? std::string() : dir + "/") + name;
    struct stat st;
    if (digits == canonical && number >= count && lstat(path.c_str(), &st) == 0 &&
        S_ISREG(st.st_mode))
      stale.push_back(path);
  }
  closedir(listing);
  std::sort(stale.begin(), stale.end());
  return stale;
}

std::string readSceneFile(const std::string& path)
{
  try
  {
    std::string text = tools::readWholeFile(path, kMaxSceneBytes, "scene file");
    // The source holds the text as a C string: a NUL would cut it short unseen.
    if (text.find('\0') != std::string::npos)
      throw InputError("cannot read scene file \"" + path + "\": it holds a NUL byte (not JSON)");
    return text;
  }
  catch (const tools::ReadInterrupted&)
  {
    throw Interrupted();
  }
  catch (const InputError&)
  {
    throw;
  }
  catch (const std::runtime_error& e)
  {
    throw InputError(e.what());
  }
}

void setSceneFile(vtkGeodesicSource* source, const std::string& path)
{
  source->SetSceneText(readSceneFile(path).c_str());
  source->SetSceneFileName(path.c_str());
}

void traceFrame(vtkGeodesicSource* source, const std::string& label, bool quiet)
{
  tools::VtkMessageCatcher messages;
  messages.watchAlgorithm(source);
  tools::ProgressBar bar(label, quiet ? tools::ProgressBar::Style::Silent
                                      : tools::ProgressBar::Style::Automatic);
  bar.watch(source);
  source->Update();
  if (tools::interruptRequested())
    throw Interrupted();
  if (messages.failed())
    throw InputError(messages.firstError());
  bar.finish();
}

std::string printable(const std::string& text)
{
  std::string out;
  for (unsigned char c : text)
  {
    if (c < 0x20 || c == 0x7f)
    {
      char escaped[8];
      std::snprintf(escaped, sizeof escaped, "\\x%02x", c);
      out += escaped;
    }
    else
      out += static_cast<char>(c);
  }
  return out;
}

std::string scenesDirectory()
{
  if (const char* dir = std::getenv("ASRT_DATA_DIR"))
    if (*dir)
      return std::string(dir) + "/scenes";
  return tools::dataDirectory() + "/scenes";
}
}
}
