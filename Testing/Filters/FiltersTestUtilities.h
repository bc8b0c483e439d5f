// Shared helpers of the VTK-layer tests: scene paths, an observer that collects error messages
// (vtkErrorMacro only reaches an observer, never a return value), and bitwise comparison of the
// per-pixel records on port 1.
#ifndef asrt_FiltersTestUtilities_h
#define asrt_FiltersTestUtilities_h

#include "vtkAbstractArray.h"
#include "vtkCommand.h"
#include "vtkDataArray.h"
#include "vtkExecutive.h"
#include "vtkGeodesicSource.h"
#include "vtkImageData.h"
#include "vtkIntArray.h"
#include "vtkNew.h"
#include "vtkPointData.h"
#include "vtkPolyData.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace asrt
{
namespace testing
{
inline std::string scenePath(const std::string& name)
{
  return std::string(ASRT_SOURCE_DIR) + "/Data/scenes/" + name;
}

inline std::string texturePath(const std::string& name)
{
  return std::string(ASRT_SOURCE_DIR) + "/Data/textures/" + name;
}

inline std::string readFile(const std::string& path)
{
  std::ifstream in(path, std::ios::binary);
  std::ostringstream os;
  os << in.rdbuf();
  return os.str();
}

/// Collects the text of every ErrorEvent and WarningEvent it observes. Attached to an algorithm
/// and to its executive, since the executive reports a failed request on its own object.
class MessageCatcher : public vtkCommand
{
public:
  static MessageCatcher* New() { return new MessageCatcher; }
  void Execute(vtkObject*, unsigned long event, void* data) override
  {
    const std::string text = data ? static_cast<const char*>(data) : "";
    (event == vtkCommand::ErrorEvent ? this->Errors : this->Warnings).push_back(text);
  }
  void Clear()
  {
    this->Errors.clear();
    this->Warnings.clear();
  }
  /// All errors in one string, for messages of failed expectations.
  std::string AllErrors() const
  {
    std::string all;
    for (const std::string& e : this->Errors)
      all += "[" + e + "] ";
    return all;
  }
  /// True if any error contains `needle`.
  bool Mentions(const std::string& needle) const
  {
    for (const std::string& e : this->Errors)
      if (e.find(needle) != std::string::npos)
        return true;
    return false;
  }
  std::vector<std::string> Errors;
  std::vector<std::string> Warnings;
};

inline void watch(vtkAlgorithm* algorithm, MessageCatcher* catcher)
{
  algorithm->AddObserver(vtkCommand::ErrorEvent, catcher);
  algorithm->AddObserver(vtkCommand::WarningEvent, catcher);
  algorithm->GetExecutive()->AddObserver(vtkCommand::ErrorEvent, catcher);
  algorithm->GetExecutive()->AddObserver(vtkCommand::WarningEvent, catcher);
}

inline vtkSmartPointer<vtkIntArray> pixelList(const std::vector<std::pair<int, int>>& ij)
{
  auto a = vtkSmartPointer<vtkIntArray>::New();
  a->SetNumberOfComponents(2);
  for (const auto& [i, j] : ij)
  {
    const int t[2] = { i, j };
    a->InsertNextTypedTuple(t);
  }
  return a;
}

/// The names of the record arrays on port 1, in the filter's documented set.
inline const std::vector<std::string>& recordArrayNames()
{
  static const std::vector<std::string> names = {
    "Pixel",     "Origin",  "Direction",  "Momentum",     "Termination", "ObjectId",
    "HitNormal", "UV",      "ChordError", "PathLength",   "Winding",     "ImageOrder",
    "Steps",     "MaxAbsH", "Color",      "RaysPerPixel", "Jacobian",    "Traced"
  };
  return names;
}

/// One pixel's record: every component of every record array plus the hit point, as raw bit
/// patterns so that NaN == NaN and -0 != +0 (the comparison is bit for bit).
using RecordBits = std::vector<std::uint64_t>;

inline std::uint64_t bitsOf(double v)
{
  std::uint64_t b;
  std::memcpy(&b, &v, sizeof b);
  return b;
}

inline double asDouble(std::uint64_t b)
{
  double v;
  std::memcpy(&v, &b, sizeof v);
  return v;
}

/// Records of port 1 keyed by pixel (i, j). Fails the current test on a duplicate pixel.
inline std::map<std::pair<int, int>, RecordBits> recordsByPixel(vtkPolyData* hits)
{
  std::map<std::pair<int, int>, RecordBits> out;
  vtkPointData* pd = hits->GetPointData();
  vtkDataArray* pixel = pd->GetArray("Pixel");
  if (!pixel)
  {
    ADD_FAILURE() << "no Pixel array";
    return out;
  }
  for (vtkIdType k = 0; k < hits->GetNumberOfPoints(); ++k)
  {
    RecordBits bits;
    double x[3];
    hits->GetPoint(k, x);
    for (double c : x)
      bits.push_back(bitsOf(c));
    for (const std::string& name : recordArrayNames())
    {
      vtkDataArray* a = pd->GetArray(name.c_str());
      if (!a)
      {
        ADD_FAILURE() << "no " << name << " array";
        continue;
      }
      for (int c = 0; c < a->GetNumberOfComponents(); ++c)
        bits.push_back(bitsOf(a->GetComponent(k, c)));
    }
    const std::pair<int, int> ij(static_cast<int>(pixel->GetComponent(k, 0)),
                                 static_cast<int>(pixel->GetComponent(k, 1)));
    if (!out.emplace(ij, std::move(bits)).second)
      ADD_FAILURE() << "pixel (" << ij.first << ", " << ij.second << ") has two records";
  }
  return out;
}

/// Names the arrays in which two records differ, for readable failures.
inline std::string describeDifference(const RecordBits& a, const RecordBits& b)
{
  if (a.size() != b.size())
    return "different numbers of values";
  std::string out;
  // Layout as in recordsByPixel: hit point, then each array's components.
  static const std::vector<std::pair<std::string, int>> layout = {
    { "hit point", 3 },    { "Pixel", 2 },       { "Origin", 3 },     { "Direction", 3 },
    { "Momentum", 4 },     { "Termination", 1 }, { "ObjectId", 1 },   { "HitNormal", 3 },
    { "UV", 2 },           { "ChordError", 1 },  { "PathLength", 1 }, { "Winding", 1 },
    { "ImageOrder", 1 },   { "Steps", 1 },       { "MaxAbsH", 1 },    { "Color", 3 },
    { "RaysPerPixel", 1 }, { "Jacobian", 4 },    { "Traced", 1 }
  };
  size_t k = 0;
  for (const auto& [name, n] : layout)
  {
    for (int c = 0; c < n && k < a.size(); ++c, ++k)
      if (a[k] != b[k])
      {
        double x, y;
        std::memcpy(&x, &a[k], sizeof x);
        std::memcpy(&y, &b[k], sizeof y);
        std::ostringstream os;
        os << name << "[" << c << "] " << x << " vs " << y << "; ";
        out += os.str();
      }
  }
  return out;
}
}
}

#endif
