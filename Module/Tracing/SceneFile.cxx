#include "SceneFile.h"

#include "AdaptiveGrid.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <set>
#include <sstream>

namespace asrt
{
namespace
{
using json = nlohmann::json;

/// Characters of a value or name quoted in a message.
constexpr std::size_t kShownLength = 60;

[[noreturn]] void fail(const std::string& path, const std::string& msg)
{
  throw InvalidParameter((path.empty() ? std::string("(document)") : path) + ": " + msg);
}

/// Text for a message: `s` itself if short, else its first characters and "...".
std::string clipped(const std::string& s, std::size_t length = kShownLength)
{
  return s.size() <= length ? s : s.substr(0, length - 3) + "...";
}

/// Appends `v` as dump() writes it until `out` holds more than `budget` characters. Neither a long
/// value nor a deep one is written whole: each level adds a character, so the recursion ends
/// within `budget` levels.
void appendBounded(const json& v, std::string& out, std::size_t budget)
{
  if (out.size() > budget)
    return;
  if (v.is_string())
  {
    // Cut before quoting; a cut through a multi-byte character is replaced, not an error.
    const std::string& text = v.get_ref<const std::string&>();
    out += json(text.substr(0, budget + 1 - out.size()))
             .dump(-1, ' ', false, json::error_handler_t::replace);
    return;
  }
  if (!v.is_structured())
  {
    out += v.dump();
    return;
  }
  out += v.is_array() ? '[' : '{';
  bool first = true;
  for (auto it = v.begin(); it != v.end() && out.size() <= budget; ++it)
  {
    if (!first)
      out += ',';
    first = false;
    if (v.is_object())
    {
      appendBounded(json(it.key()), out, budget);
      out += ':';
    }
    appendBounded(*it, out, budget);
  }
  out += v.is_array() ? ']' : '}';
}

/// A JSON value as written, shortened for messages.
std::string show(const json& v)
{
  std::string s;
  appendBounded(v, s, kShownLength);
  return clipped(s);
}

std::string typeName(const json& v)
{
  return v.type_name();
}

/// Levenshtein distance, for "did you mean" hints on misspelt keys.
std::size_t editDistance(const std::string& a, const std::string& b)
{
  std::vector<std::size_t> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j)
    row[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i)
  {
    std::size_t diag = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j)
    {
      const std::size_t up = row[j];
      const bool same = std::tolower(static_cast<unsigned char>(a[i - 1])) ==
                        std::tolower(static_cast<unsigned char>(b[j - 1]));
      row[j] = std::min({ row[j] + 1, row[j - 1] + 1, diag + (same ? 0 : 1) });
      diag = up;
    }
  }
  return row[b.size()];
}

std::string joined(const std::vector<std::string>& names)
{
  std::string s;
  for (const std::string& n : names)
    s += (s.empty() ? "" : ", ") + n;
  return s;
}

/// A JSON object being read: knows its path and its allowed keys, and refuses any other key up
/// front, so that a misspelt optional field is an error instead of a silently ignored default (and
/// a misspelt required one is reported as the typo, not as missing).
class Fields
{
public:
  Fields(const json& j, std::string path, std::vector<std::string> known)
    : J(j)
    , Path(std::move(path))
    , Known(std::move(known))
  {
    if (!j.is_object())
      fail(this->Path, "must be an object, got " + typeName(j) + " " + show(j));
    this->refuseUnknown();
  }

  const std::string& path() const { return this->Path; }
  std::string sub(const std::string& key) const
  {
    return this->Path.empty() ? key : this->Path + "." + key;
  }
  bool has(const std::string& key) const { return this->J.contains(key); }

  /// The value of an optional field, or null if absent.
  const json* get(const std::string& key) const
  {
    const auto it = this->J.find(key);
    return it == this->J.end() ? nullptr : &*it;
  }
  const json& require(const std::string& key) const
  {
    const json* v = this->get(key);
    if (!v)
      fail(this->sub(key), "required field is missing");
    return *v;
  }

private:
  void refuseUnknown() const
  {
    for (const auto& item : this->J.items())
    {
      const std::string& key = item.key();
      if (std::find(this->Known.begin(), this->Known.end(), key) != this->Known.end())
        continue;
      std::string msg = "unknown field";
      std::size_t best = 3; // at most two edits count as a likely typo
      std::string hint;
      for (const std::string& k : this->Known)
      {
        const std::size_t d = editDistance(key, k);
        if (d < best)
        {
          best = d;
          hint = k;
        }
      }
      if (!hint.empty())
        msg += " (did you mean \"" + hint + "\"?)";
      msg += "; known fields: " + joined(this->Known);
      fail(this->sub(clipped(key)), msg);
    }
  }

  const json& J;
  std::string Path;
  std::vector<std::string> Known;
};

// ---- scalar readers: each names the field and shows what it got -----------------------------
double number(const json& v, const std::string& path)
{
  if (!v.is_number())
    fail(path, "must be a number, got " + typeName(v) + " " + show(v));
  const double x = v.get<double>();
  if (!std::isfinite(x))
    fail(path, "must be finite, got a number that overflows a double");
  return x;
}

double positive(const json& v, const std::string& path)
{
  const double x = number(v, path);
  if (!(x > 0.0))
    fail(path, "must be positive, got " + show(v));
  return x;
}

double nonNegative(const json& v, const std::string& path)
{
  const double x = number(v, path);
  if (!(x >= 0.0))
    fail(path, "must be non-negative, got " + show(v));
  return x;
}

/// An integer in [lo, hi]; integral floats (200.0) are accepted, 200.5 is not.
long long integer(const json& v, const std::string& path, long long lo, long long hi)
{
  std::ostringstream what;
  if (lo == 1)
    what << "must be a positive integer";
  else if (lo == 0)
    what << "must be a non-negative integer";
  else
    what << "must be an integer";
  auto refuse = [&](bool showType, bool tooLarge = false)
  {
    std::ostringstream os;
    os << what.str();
    if (tooLarge)
      os << " no larger than " << hi;
    os << ", got " << (showType ? typeName(v) + " " : "") << show(v);
    fail(path, os.str());
  };
  long long n = 0;
  if (v.is_number_unsigned())
  {
    const auto u = v.get<unsigned long long>();
    if (u > static_cast<unsigned long long>(hi))
      refuse(false, true);
    n = static_cast<long long>(u);
  }
  else if (v.is_number_integer())
    n = v.get<long long>();
  else if (v.is_number_float())
  {
    const double x = v.get<double>();
    if (!(std::isfinite(x) && x == std::floor(x) && std::abs(x) < 9e18))
      refuse(false);
    n = static_cast<long long>(x);
  }
  else
    refuse(true);
  if (n < lo || n > hi)
    refuse(false, n > hi);
  return n;
}

bool boolean(const json& v, const std::string& path)
{
  if (!v.is_boolean())
    fail(path, "must be true or false, got " + typeName(v) + " " + show(v));
  return v.get<bool>();
}

std::string str(const json& v, const std::string& path, bool nonEmpty = false)
{
  if (!v.is_string())
    fail(path, "must be a string, got " + typeName(v) + " " + show(v));
  std::string s = v.get<std::string>();
  if (nonEmpty && s.empty())
    fail(path, "must not be empty");
  return s;
}

const json& array(const json& v, const std::string& path, std::size_t size, const char* what)
{
  if (!v.is_array() || (size > 0 && v.size() != size))
    fail(path, std::string("must be ") + what + ", got " + typeName(v) + " " + show(v));
  return v;
}

std::string index(const std::string& path, std::size_t i)
{
  return path + "[" + std::to_string(i) + "]";
}

Vec3 vec3(const json& v, const std::string& path)
{
  array(v, path, 3, "an array of 3 numbers");
  Vec3 x;
  for (std::size_t i = 0; i < 3; ++i)
    x[i] = number(v[i], index(path, i));
  return x;
}

Vec3 direction(const json& v, const std::string& path)
{
  const Vec3 x = vec3(v, path);
  if (!(x.norm() > 1e-150))
    fail(path, "must be a nonzero vector (norm above 1e-150), got " + show(v));
  return x;
}

Color color(const json& v, const std::string& path)
{
  array(v, path, 3, "an RGB array of 3 numbers in [0, 1]");
  Color c;
  for (std::size_t i = 0; i < 3; ++i)
  {
    c[i] = number(v[i], index(path, i));
    if (!(c[i] >= 0.0 && c[i] <= 1.0))
      fail(index(path, i), "must lie in [0, 1], got " + show(v[i]));
  }
  return c;
}

/// For each number of `text` written with a fraction or an exponent whose value is zero or
/// subnormal, in the order of the document: whether strtod reports it out of range (ERANGE), as
/// 1e-400 is. nlohmann reads such a number as 0 without a word; StructureCheck matches these, one
/// by one, to the zero and subnormal values it sees, and so names the field.
std::vector<bool> tinyNumbersUnderflowing(const std::string& text)
{
  std::vector<bool> underflows;
  for (std::size_t k = 0; k < text.size(); ++k)
  {
    const char c = text[k];
    if (c == '"')
    {
      for (++k; k < text.size() && text[k] != '"'; ++k)
        if (text[k] == '\\')
          ++k;
      continue;
    }
    if (c != '-' && !std::isdigit(static_cast<unsigned char>(c)))
      continue;
    std::size_t end = k;
    bool isFloat = false;
    while (end < text.size() && std::strchr("0123456789+-.eE", text[end]) && text[end] != '\0')
    {
      isFloat = isFloat || text[end] == '.' || text[end] == 'e' || text[end] == 'E';
      ++end;
    }
    if (isFloat)
    {
      const std::string lexeme = text.substr(k, end - k);
      errno = 0;
      const double v = std::strtod(lexeme.c_str(), nullptr);
      if (v == 0.0 || std::fpclassify(v) == FP_SUBNORMAL)
        underflows.push_back(errno == ERANGE);
    }
    k = end - 1;
  }
  return underflows;
}

// ---- the sections ---------------------------------------------------------------------------
/// Checks the document while nlohmann parses it: rejects duplicate keys, which nlohmann would
/// otherwise resolve silently (the last one wins), and nesting deeper than kMaxSceneNesting,
/// before the deep value exists. Tracks the path of the value being parsed to name the culprit.
class StructureCheck
{
public:
  bool operator()(int depth, json::parse_event_t event, json& parsed)
  {
    switch (event)
    {
      case json::parse_event_t::object_start:
      case json::parse_event_t::array_start:
        // `depth` counts the containers around this one.
        if (depth >= kMaxSceneNesting)
          fail(clipped(this->path()), "arrays and objects nested more than " +
                                        std::to_string(kMaxSceneNesting) +
                                        " levels deep (a scene needs 6)");
        this->Frames.push_back({ event == json::parse_event_t::array_start, 0, {}, {} });
        break;
      case json::parse_event_t::key:
      {
        Frame& top = this->Frames.back();
        top.key = parsed.get<std::string>();
        if (!top.keys.insert(top.key).second)
          fail(clipped(this->path(), 4 * kShownLength),
               "duplicate field (given twice in one object)");
        break;
      }
      case json::parse_event_t::object_end:
      case json::parse_event_t::array_end:
        this->Frames.pop_back();
        this->valueDone();
        break;
      case json::parse_event_t::value:
        this->checkTinyNumber(parsed);
        this->valueDone();
        break;
    }
    return true;
  }

  /// The result of tinyNumbersUnderflowing for the document being parsed.
  std::vector<bool> TinyNumbersUnderflow;

  /// Where the parser is: the path of the value being read.
  std::string path() const
  {
    std::string p;
    for (const Frame& f : this->Frames)
    {
      if (f.isArray)
        p += "[" + std::to_string(f.index) + "]";
      else
        p += (p.empty() ? "" : ".") + clipped(f.key);
    }
    return p;
  }

private:
  struct Frame
  {
    bool isArray;
    std::size_t index;
    std::string key;
    std::set<std::string> keys;
  };
  void checkTinyNumber(const json& parsed)
  {
    if (!parsed.is_number_float())
      return;
    const double v = parsed.get<double>();
    if (v != 0.0 && std::fpclassify(v) != FP_SUBNORMAL)
      return;
    const std::size_t k = this->TinyNumbers++;
    if (k < this->TinyNumbersUnderflow.size() && this->TinyNumbersUnderflow[k])
      fail(clipped(this->path(), 4 * kShownLength),
           "a number too small for a double (it underflows, and would be read as " +
             exactNumber(v) + ")");
  }
  std::size_t TinyNumbers = 0;
  void valueDone()
  {
    if (!this->Frames.empty() && this->Frames.back().isArray)
      ++this->Frames.back().index;
  }
  std::vector<Frame> Frames;
};

std::string resolvePath(const std::string& file, const std::string& baseDir)
{
  namespace fs = std::filesystem;
  const fs::path p(file);
  if (p.is_absolute() || baseDir.empty())
    return p.lexically_normal().string();
  return (fs::path(baseDir) / p).lexically_normal().string();
}

class Parser
{
public:
  Parser(std::string baseDir, const ImageLoader& loader)
    : BaseDir(std::move(baseDir))
    , Loader(loader)
  {
  }
  SceneOrigin Origin = SceneOrigin::User;

  SceneDescription parse(const std::string& text)
  {
    if (text.size() > kMaxSceneBytes)
      fail("(document)", "the scene's " + std::to_string(text.size()) + " bytes exceed the " +
                           std::to_string(kMaxSceneBytes >> 20) + " MiB a scene may have");
    json doc;
    StructureCheck check;
    check.TinyNumbersUnderflow = tinyNumbersUnderflowing(text);
    try
    {
      doc = json::parse(text, std::ref(check));
    }
    catch (const json::parse_error& e)
    {
      // nlohmann's message carries the line and column first, then the token last read (cut: it
      // may be an unterminated string of the whole file).
      fail("(document)", "malformed JSON: " + clipped(e.what(), 4 * kShownLength));
    }
    catch (const json::exception& e)
    {
      // A number too large for a double (JSON has no NaN or infinity, but 1e400 overflows).
      fail(clipped(check.path(), 4 * kShownLength),
           "must be finite, got a number that overflows a double (" +
             clipped(e.what(), 2 * kShownLength) + ")");
    }
    SceneDescription d;
    Fields root(doc, "",
                { "name", "description", "spacetime", "camera", "integrator", "tracing",
                  "background", "horizonColor", "objects", "rendering", "subset" });
    if (const json* v = root.get("name"))
      d.name = str(*v, "name");
    if (const json* v = root.get("description"))
      str(*v, "description");

    this->spacetime(root.require("spacetime"), d);
    const auto st = makeSpacetime(d.spacetime);
    this->camera(root.require("camera"), d, *st);
    if (const json* v = root.get("integrator"))
      this->integrator(*v, d, *st);
    if (const json* v = root.get("tracing"))
      this->tracing(*v, d);
    if (const json* v = root.get("background"))
      d.scene->background = color(*v, "background");
    if (const json* v = root.get("horizonColor"))
      d.scene->horizonColor = color(*v, "horizonColor");
    this->objects(root.require("objects"), d);
    // A text without the section was traced before anti-aliasing existed, one ray a pixel; the
    // store gives such stored texts the section (schema version 5), so only hand-written scenes
    // come here without it, and they get the default.
    if (const json* v = root.get("rendering"))
      this->rendering(*v, d);
    validateRendering(d.rendering, static_cast<long long>(d.camera.width) * d.camera.height);
    if (const json* v = root.get("subset"))
    {
      if (this->Origin != SceneOrigin::Program)
        fail("subset", "is written by the program for the pixels it traces alone, never given "
                       "in a scene (trace a subset with vtkGeodesicSource's PixelSubset)");
      d.subset = subset(*v);
    }
    d.sourceText = doc.dump();
    return d;
  }

private:
  static PixelSubsetId subset(const json& j)
  {
    Fields f(j, "subset", { "pixels", "digest", "border" });
    PixelSubsetId s;
    s.count = integer(f.require("pixels"), f.sub("pixels"), 1, kMaxFramePixels);
    auto digest = [&](const char* key)
    {
      const std::string d = str(f.require(key), f.sub(key));
      const bool hex =
        d.size() == 16 &&
        std::all_of(d.begin(), d.end(),
                    [](char c) { return std::isxdigit(static_cast<unsigned char>(c)); });
      if (!hex)
        fail(f.sub(key), "must be 16 hexadecimal digits, got " + show(f.require(key)));
      return d;
    };
    s.digest = digest("digest");
    if (f.get("border"))
      s.border = digest("border");
    return s;
  }

  void spacetime(const json& j, SceneDescription& d)
  {
    Fields f(j, "spacetime", { "mass", "spin", "charge" });
    d.spacetime.mass = number(f.require("mass"), f.sub("mass"));
    if (const json* v = f.get("spin"))
      d.spacetime.spin = number(*v, f.sub("spin"));
    if (const json* v = f.get("charge"))
      d.spacetime.charge = number(*v, f.sub("charge"));
    validateSpacetime(d.spacetime); // the rules overrides of the values follow too
  }

  void camera(const json& j, SceneDescription& d, const Spacetime& st)
  {
    Fields f(j, "camera",
             { "position", "focalPoint", "viewUp", "viewAngle", "resolution", "observer" });
    CameraParameters& c = d.camera;
    c.position = vec3(f.require("position"), f.sub("position"));
    c.focalPoint = vec3(f.require("focalPoint"), f.sub("focalPoint"));
    if (const json* v = f.get("viewUp"))
      c.viewUp = direction(*v, f.sub("viewUp"));
    if (const json* v = f.get("viewAngle"))
      c.viewAngle = number(*v, f.sub("viewAngle"));
    if (const json* v = f.get("resolution"))
    {
      const std::string p = f.sub("resolution");
      array(*v, p, 2, "[width, height], two positive integers");
      const int maxInt = std::numeric_limits<int>::max();
      c.width = static_cast<int>(integer((*v)[0], index(p, 0), 1, maxInt));
      c.height = static_cast<int>(integer((*v)[1], index(p, 1), 1, maxInt));
    }
    if (const json* v = f.get("observer"))
    {
      const std::string s = str(*v, f.sub("observer"));
      if (s == "static")
        c.observer = ObserverMotion::Static;
      else if (s == "zamo")
        c.observer = ObserverMotion::ZAMO;
      else
        fail(f.sub("observer"), "must be \"static\" or \"zamo\", got " + show(*v));
    }

    validateCamera(c, st);
  }

  void integrator(const json& j, SceneDescription& d, const Spacetime& st)
  {
    Fields f(j, "integrator",
             { "preset", "method", "step", "timeTransform", "omega", "relativeTolerance",
               "absoluteTolerance" });
    IntegratorConfig& c = d.integrator;
    // A preset sets every field first; the fields given beside it refine it.
    if (const json* v = f.get("preset"))
    {
      try
      {
        // A name longer than any preset's is passed cut, so that the message quoting it is short.
        c = integratorPreset(clipped(str(*v, f.sub("preset"), true)));
      }
      catch (const InvalidParameter& e)
      {
        fail(f.sub("preset"), e.what());
      }
    }
    if (const json* v = f.get("method"))
    {
      c.method = str(*v, f.sub("method"), true);
      if (c.method != "auto")
      {
        try
        {
          findMethod(clipped(c.method));
        }
        catch (const InvalidParameter& e)
        {
          fail(f.sub("method"), e.what());
        }
      }
    }
    if (const json* v = f.get("step"))
      c.step = positive(*v, f.sub("step"));
    if (const json* v = f.get("timeTransform"))
      c.timeTransform = boolean(*v, f.sub("timeTransform"));
    if (const json* v = f.get("omega"))
      c.omega = positive(*v, f.sub("omega"));
    if (const json* v = f.get("relativeTolerance"))
      c.relativeTolerance = positive(*v, f.sub("relativeTolerance"));
    if (const json* v = f.get("absoluteTolerance"))
      c.absoluteTolerance = positive(*v, f.sub("absoluteTolerance"));
    validateIntegrator(c, st);
  }

  static void rendering(const json& j, SceneDescription& d)
  {
    Fields f(j, "rendering",
             { "preset", "antialias", "maxRaysPerPixel", "supersample", "colorThreshold",
               "gridLattice", "gridTolerance" });
    AntialiasOptions& o = d.rendering;
    // A preset sets every field first; the fields given beside it refine it.
    if (const json* v = f.get("preset"))
    {
      try
      {
        o = renderingPreset(clipped(str(*v, f.sub("preset"), true)));
      }
      catch (const InvalidParameter& e)
      {
        fail(f.sub("preset"), e.what());
      }
    }
    if (const json* v = f.get("antialias"))
    {
      try
      {
        o.mode = antialiasModeFromString(clipped(str(*v, f.sub("antialias"), true)));
      }
      catch (const InvalidParameter& e)
      {
        fail(f.sub("antialias"), e.what());
      }
    }
    if (const json* v = f.get("maxRaysPerPixel"))
      o.maxRaysPerPixel =
        static_cast<int>(integer(*v, f.sub("maxRaysPerPixel"), 1, kMaxRaysPerPixel));
    if (const json* v = f.get("supersample"))
      o.supersample = static_cast<int>(integer(*v, f.sub("supersample"), 1, 32));
    if (const json* v = f.get("colorThreshold"))
    {
      o.colorThreshold = nonNegative(*v, f.sub("colorThreshold"));
      if (o.colorThreshold > 1.0)
        fail(f.sub("colorThreshold"), "must lie in [0, 1], got " + show(*v));
    }
    if (const json* v = f.get("gridLattice"))
      o.gridLattice = static_cast<int>(integer(*v, f.sub("gridLattice"), 1, kMaxGridLattice));
    if (const json* v = f.get("gridTolerance"))
      o.gridTolerance = nonNegative(*v, f.sub("gridTolerance"));
  }

  void tracing(const json& j, SceneDescription& d)
  {
    Fields f(j, "tracing", { "escapeRadius", "maxSteps", "horizonEpsilon", "maxHamiltonianError" });
    TraceOptions& t = d.tracing;
    if (const json* v = f.get("escapeRadius"))
      t.escapeRadius = positive(*v, f.sub("escapeRadius"));
    if (const json* v = f.get("maxSteps"))
      t.maxSteps =
        static_cast<long>(integer(*v, f.sub("maxSteps"), 1, std::numeric_limits<long>::max() / 2));
    if (const json* v = f.get("horizonEpsilon"))
      t.horizonEpsilon = positive(*v, f.sub("horizonEpsilon"));
    if (const json* v = f.get("maxHamiltonianError"))
      t.maxHamiltonianError = positive(*v, f.sub("maxHamiltonianError"));
    validateTracing(t);
  }

  std::shared_ptr<const Texture> texture(const json& j, const std::string& path)
  {
    Fields f(j, path, { "color", "checker", "colors", "image" });
    const int kinds = f.has("color") + f.has("checker") + f.has("image");
    if (kinds != 1)
      fail(path, "give exactly one of \"color\", \"checker\" or \"image\", got " + show(j));
    if (f.has("colors") && !f.has("checker"))
      fail(f.sub("colors"), "belongs to a \"checker\" texture");
    std::shared_ptr<const Texture> t;
    if (const json* v = f.get("color"))
      t = std::make_shared<SolidTexture>(color(*v, f.sub("color")));
    else if (const json* v = f.get("checker"))
    {
      const std::string p = f.sub("checker");
      array(*v, p, 2, "[nu, nv], two positive integers");
      const int nu = static_cast<int>(integer((*v)[0], index(p, 0), 1, 1 << 20));
      const int nv = static_cast<int>(integer((*v)[1], index(p, 1), 1, 1 << 20));
      Color a(1, 1, 1), b(0, 0, 0);
      if (const json* c = f.get("colors"))
      {
        const std::string cp = f.sub("colors");
        array(*c, cp, 2, "two RGB colours [[r, g, b], [r, g, b]]");
        a = color((*c)[0], index(cp, 0));
        b = color((*c)[1], index(cp, 1));
      }
      t = std::make_shared<CheckerTexture>(nu, nv, a, b);
    }
    else
    {
      const std::string p = f.sub("image");
      const std::string file = str(f.require("image"), p, true);
      // No file name holds a NUL; left in, it would also end every message that quotes the name.
      if (file.find('\0') != std::string::npos)
        fail(p, "a file name cannot hold a NUL character, got " + show(f.require("image")));
      t = this->image(file, p);
    }
    return t;
  }

  std::shared_ptr<const Texture> image(const std::string& file, const std::string& path)
  {
    const std::string resolved = resolvePath(file, this->BaseDir);
    const auto cached = this->Images.find(resolved);
    if (cached != this->Images.end())
      return cached->second;
    const std::string what =
      "cannot read \"" + clipped(file, 2 * kShownLength) + "\"" +
      (resolved != file ? " (resolved to \"" + clipped(resolved, 2 * kShownLength) + "\")"
                        : std::string());
    if (!this->Loader)
      fail(path, what + ": no image loader was given");
    ImagePixels px;
    try
    {
      px = this->Loader(resolved);
    }
    catch (const std::exception& e)
    {
      fail(path, what + ": " + clipped(e.what(), 6 * kShownLength));
    }
    std::shared_ptr<const Texture> t;
    try
    {
      t = std::make_shared<ImageTexture>(px.width, px.height, std::move(px.rgb));
    }
    catch (const InvalidParameter& e)
    {
      fail(path, what + ": " + e.what());
    }
    this->Images.emplace(resolved, t);
    return t;
  }

  void objects(const json& j, SceneDescription& d)
  {
    array(j, "objects", 0, "an array of objects");
    if (j.size() > kMaxSceneObjects)
      fail("objects", "holds " + std::to_string(j.size()) + " objects; a scene may have at most " +
                        std::to_string(kMaxSceneObjects));
    std::map<long long, std::size_t> ids;
    for (std::size_t i = 0; i < j.size(); ++i)
    {
      const std::string p = index("objects", i);
      const json& o = j[i];
      if (!o.is_object())
        fail(p, "must be an object, got " + typeName(o) + " " + show(o));
      const auto typeIt = o.find("type");
      if (typeIt == o.end())
        fail(p + ".type", "required field is missing");
      const std::string type = str(*typeIt, p + ".type");
      std::vector<std::string> known{ "type", "id", "name", "texture" };
      const auto spec = Parser::specificFields(type);
      if (!spec)
        fail(p + ".type",
             "unknown object type \"" + clipped(type) +
               "\" (known: celestialSphere, plane, rectangle, cylinder, sphere, disk)");
      known.insert(known.end(), spec->begin(), spec->end());
      Fields f(o, p, known);
      const long long id =
        integer(f.require("id"), f.sub("id"), 0, std::numeric_limits<int>::max());
      const auto seen = ids.find(id);
      if (seen != ids.end())
        fail(f.sub("id"), "duplicate id " + std::to_string(id) + " (already used by objects[" +
                            std::to_string(seen->second) + "])");
      ids.emplace(id, i);
      std::string name = type + std::to_string(id);
      if (const json* v = f.get("name"))
        name = str(*v, f.sub("name"), true);
      const auto tex = this->texture(f.require("texture"), f.sub("texture"));
      std::unique_ptr<SceneObject> obj = this->object(type, f, static_cast<int>(id), name, tex, d);
      d.scene->add(std::move(obj));
    }
  }

  static const std::vector<std::string>* specificFields(const std::string& type)
  {
    static const std::map<std::string, std::vector<std::string>> table{
      { "celestialSphere", { "radius" } },
      { "plane", { "center", "uAxis", "vAxis", "tile" } },
      { "rectangle", { "center", "uAxis", "vAxis", "halfWidth", "halfHeight" } },
      { "cylinder", { "base", "axis", "radius", "height" } },
      { "sphere", { "center", "radius" } },
      { "disk", { "center", "normal", "innerRadius", "outerRadius" } },
    };
    const auto it = table.find(type);
    return it == table.end() ? nullptr : &it->second;
  }

  std::unique_ptr<SceneObject> object(const std::string& type, const Fields& f, int id,
                                      const std::string& name,
                                      const std::shared_ptr<const Texture>& tex,
                                      const SceneDescription& d)
  {
    auto num = [&f](const char* key, double (*read)(const json&, const std::string&))
    { return read(f.require(key), f.sub(key)); };
    auto vec = [&f](const char* key) { return vec3(f.require(key), f.sub(key)); };
    auto dir = [&f](const char* key) { return direction(f.require(key), f.sub(key)); };
    try
    {
      if (type == "celestialSphere")
      {
        const double R = num("radius", positive);
        validateCelestialSphere(R, d.camera.position, f.sub("radius"));
        return std::make_unique<CelestialSphere>(id, name, tex, R);
      }
      if (type == "plane" || type == "rectangle")
      {
        const Vec3 c = vec("center");
        const Vec3 u = dir("uAxis"), v = dir("vAxis");
        if (u.normalized().cross(v.normalized()).norm() < 1e-9)
          fail(f.sub("vAxis"), "must not be parallel to uAxis");
        if (type == "plane")
        {
          double tile = 1.0;
          if (const json* t = f.get("tile"))
            tile = positive(*t, f.sub("tile"));
          const double inf = std::numeric_limits<double>::infinity();
          return std::make_unique<Rectangle>(id, name, tex, c, u, v, inf, inf, tile);
        }
        const double hw = num("halfWidth", positive), hh = num("halfHeight", positive);
        return std::make_unique<Rectangle>(id, name, tex, c, u, v, hw, hh);
      }
      if (type == "cylinder")
      {
        const Vec3 base = vec("base"), axis = dir("axis");
        const double R = num("radius", positive), H = num("height", positive);
        return std::make_unique<Cylinder>(id, name, tex, base, axis, R, H);
      }
      if (type == "sphere")
      {
        const Vec3 c = vec("center");
        return std::make_unique<Sphere>(id, name, tex, c, num("radius", positive));
      }
      // disk
      const Vec3 c = vec("center"), n = dir("normal");
      const double rin = num("innerRadius", nonNegative), rout = num("outerRadius", positive);
      if (!(rout > rin))
        fail(f.sub("outerRadius"), "must exceed innerRadius (" + show(f.require("innerRadius")) +
                                     "), got " + show(f.require("outerRadius")));
      return std::make_unique<Disk>(id, name, tex, c, n, rin, rout);
    }
    catch (const InvalidParameter& e)
    {
      // Field errors above already carry their path; a constructor's check does not.
      const std::string msg = e.what();
      if (msg.rfind(f.path(), 0) == 0)
        throw;
      fail(f.path(), msg);
    }
  }

  std::string BaseDir;
  const ImageLoader& Loader;
  std::map<std::string, std::shared_ptr<const Texture>> Images;
};
}

SceneDescription parseScene(const std::string& jsonText, const std::string& baseDir,
                            const ImageLoader& loader, SceneOrigin origin)
{
  Parser parser(baseDir, loader);
  parser.Origin = origin;
  return parser.parse(jsonText);
}

SceneDescription loadSceneFile(const std::string& path, const ImageLoader& loader)
{
  std::ifstream in(path, std::ios::binary);
  if (!in || std::filesystem::is_directory(path))
    throw InvalidParameter("cannot read scene file \"" + path + "\"");
  // In chunks, up to one byte past the bound: /dev/zero or an endless pipe stops there.
  std::string text;
  std::vector<char> chunk(1 << 20);
  while (in)
  {
    in.read(chunk.data(), static_cast<std::streamsize>(chunk.size()));
    text.append(chunk.data(), static_cast<std::size_t>(in.gcount()));
    if (text.size() > kMaxSceneBytes)
      throw InvalidParameter("scene file \"" + path + "\" is larger than " +
                             std::to_string(kMaxSceneBytes >> 20) + " MiB (" +
                             std::to_string(kMaxSceneBytes) + " bytes), the most a scene may hold");
  }
  if (in.bad())
    throw InvalidParameter("cannot read scene file \"" + path + "\"");
  const std::string dir = std::filesystem::path(path).parent_path().string();
  try
  {
    return parseScene(text, dir, loader);
  }
  catch (const InvalidParameter& e)
  {
    throw InvalidParameter(path + ": " + e.what());
  }
}
std::string effectiveSceneText(const SceneDescription& d)
{
  json j = d.sourceText.empty() ? json::object() : json::parse(d.sourceText);
  auto vec = [](const Vec3& v) { return json::array({ v.x(), v.y(), v.z() }); };
  const SpacetimeParameters& st = d.spacetime;
  j["spacetime"] = { { "mass", st.mass }, { "spin", st.spin }, { "charge", st.charge } };
  json& cam = j["camera"];
  cam["position"] = vec(d.camera.position);
  cam["focalPoint"] = vec(d.camera.focalPoint);
  cam["viewUp"] = vec(d.camera.viewUp);
  cam["viewAngle"] = d.camera.viewAngle;
  cam["resolution"] = json::array({ d.camera.width, d.camera.height });
  cam["observer"] = toString(d.camera.observer);
  const IntegratorConfig& c = d.integrator;
  j["integrator"] = { { "method", c.method },
                      { "step", c.step },
                      { "timeTransform", c.timeTransform },
                      { "omega", c.omega },
                      { "relativeTolerance", c.relativeTolerance },
                      { "absoluteTolerance", c.absoluteTolerance } };
  const TraceOptions& t = d.tracing;
  j["tracing"] = { { "escapeRadius", t.escapeRadius },
                   { "maxSteps", t.maxSteps },
                   { "horizonEpsilon", t.horizonEpsilon },
                   { "maxHamiltonianError", t.maxHamiltonianError } };
  const AntialiasOptions& a = d.rendering;
  j["rendering"] = { { "antialias", toString(a.mode) },
                     { "maxRaysPerPixel", a.maxRaysPerPixel },
                     { "supersample", a.supersample },
                     { "colorThreshold", a.colorThreshold } };
  // The lattice is always written: a text without it reads as the default grid, which frames
  // stored before the grid existed (their texts gain "gridLattice": 1 in schema version 7) were
  // not traced with. The tolerance means nothing without a grid.
  j["rendering"]["gridLattice"] = effectiveGridLattice(a);
  if (effectiveGridLattice(a) > 1)
    j["rendering"]["gridTolerance"] = a.gridTolerance;
  // Whole frames keep exactly the text they always had; a subset frame is a frame of its own.
  if (d.subset.count > 0)
  {
    j["subset"] = { { "pixels", d.subset.count }, { "digest", d.subset.digest } };
    // Pixels traced beside given neighbours are a subset of their own; others keep their text.
    if (!d.subset.border.empty())
      j["subset"]["border"] = d.subset.border;
  }
  else
    j.erase("subset");
  return j.dump();
}
ImageLoader neutralImageLoader()
{
  return [](const std::string&)
  {
    ImagePixels px;
    px.width = px.height = 1;
    px.rgb = { 128, 128, 128 };
    return px;
  };
}

SceneDescription parseSceneWithoutImages(const std::string& jsonText)
{
  return parseScene(jsonText, ".", neutralImageLoader(), SceneOrigin::Program);
}
}
