// vtkGeodesicSource as a pipeline citizen: what its three ports hold, how overrides, pieces, pixel
// subsets and polylines relate to one full frame, progress and abort, and how bad input is
// reported. The Fig. 1 scene at 32 × 32 is traced once and shared: every other run is compared
// with it, so that a disagreement shows up as a difference between two outputs of the filter.
#include "FiltersTestUtilities.h"
#include "Propagator.h"

#include "vtkCellArray.h"
#include "vtkCellData.h"
#include "vtkDoubleArray.h"
#include "vtkFieldData.h"
#include "vtkIdList.h"
#include "vtkInformation.h"
#include "vtkStreamingDemandDrivenPipeline.h"
#include "vtkStringArray.h"
#include "vtkUnsignedCharArray.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <limits>
#include <set>

#include <omp.h>

using asrt::testing::MessageCatcher;
using asrt::testing::pixelList;
using asrt::testing::RecordBits;
using asrt::testing::recordsByPixel;
using asrt::testing::scenePath;
using Pixel = std::pair<int, int>;

namespace
{
constexpr int kW = 32;
constexpr int kH = 32;
const double kNaN = std::numeric_limits<double>::quiet_NaN();

double secondsSince(std::chrono::steady_clock::time_point t0)
{
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

/// Records every progress value the filter announces.
class ProgressRecorder : public vtkCommand
{
public:
  static ProgressRecorder* New() { return new ProgressRecorder; }
  void Execute(vtkObject*, unsigned long, void* data) override
  {
    this->Values.push_back(*static_cast<double*>(data));
  }
  std::vector<double> Values;
};

/// Asks the filter to stop at the first progress event it sees.
class AbortAtFirstProgress : public vtkCommand
{
public:
  static AbortAtFirstProgress* New() { return new AbortAtFirstProgress; }
  void Execute(vtkObject* caller, unsigned long, void* data) override
  {
    ++this->Events;
    // The trace reports at most 0.95 (its share of the work); a report of exactly 1 (the run's end,
    // which newer VTK's executive reports after aborted runs too) says nothing of how far it went.
    if (data && *static_cast<double*>(data) < 1.0)
      this->Largest = std::max(this->Largest, *static_cast<double*>(data));
    if (this->Events == 1)
      vtkAlgorithm::SafeDownCast(caller)->SetAbortExecute(1);
  }
  int Events = 0;
  double Largest = 0; ///< the largest fraction done that was reported
};

/// A deep copy of one run's ports 0 and 1, with what was reported during the run.
struct Frame
{
  vtkSmartPointer<vtkImageData> image;
  vtkSmartPointer<vtkPolyData> hits;
  std::vector<double> progress;
  std::vector<std::string> errors;
};

Frame traceFrame(const std::function<void(vtkGeodesicSource*)>& configure)
{
  vtkNew<vtkGeodesicSource> source;
  vtkNew<MessageCatcher> catcher;
  asrt::testing::watch(source, catcher);
  vtkNew<ProgressRecorder> progress;
  source->AddObserver(vtkCommand::ProgressEvent, progress);
  configure(source);
  source->Update();
  Frame f;
  f.image = vtkSmartPointer<vtkImageData>::New();
  f.image->DeepCopy(source->GetImageOutput());
  f.hits = vtkSmartPointer<vtkPolyData>::New();
  f.hits->DeepCopy(source->GetHitsOutput());
  f.progress = progress->Values;
  f.errors = catcher->Errors;
  return f;
}

/// The reference: Fig. 1 at 32 × 32, traced whole, once.
const Frame& fig1Frame()
{
  static const Frame frame = traceFrame(
    [](vtkGeodesicSource* s)
    {
      s->SetSceneFileName(scenePath("fig1-cylinders.json").c_str());
      s->SetResolution(kW, kH);
    });
  return frame;
}

const std::map<Pixel, RecordBits>& fig1Records()
{
  static const std::map<Pixel, RecordBits> records = recordsByPixel(fig1Frame().hits);
  return records;
}

/// The point of pixel (i, j), or −1 if the image's extent does not hold it (ComputePointId
/// itself does not check).
vtkIdType pointOf(vtkImageData* image, int i, int j)
{
  int ext[6];
  image->GetExtent(ext);
  if (i < ext[0] || i > ext[1] || j < ext[2] || j > ext[3])
    return -1;
  int ijk[3] = { i, j, 0 };
  return image->ComputePointId(ijk);
}

double fieldValue(vtkPolyData* hits, const char* name, int component = 0)
{
  vtkDataArray* a = hits->GetFieldData()->GetArray(name);
  return a && a->GetNumberOfTuples() > 0 && component < a->GetNumberOfComponents()
           ? a->GetComponent(0, component)
           : kNaN;
}

std::string fieldString(vtkPolyData* hits, const char* name)
{
  auto* a = vtkStringArray::SafeDownCast(hits->GetFieldData()->GetAbstractArray(name));
  return a && a->GetNumberOfValues() > 0 ? a->GetValue(0) : std::string("(missing)");
}

/// Compares records with the reference frame's for the same pixels, bit for bit; the message
/// lists the first few disagreements by field.
void expectRecordsMatchReference(const std::map<Pixel, RecordBits>& records, const char* what)
{
  const auto& reference = fig1Records();
  int differing = 0;
  std::string examples;
  for (const auto& [ij, bits] : records)
  {
    auto it = reference.find(ij);
    if (it == reference.end())
    {
      ADD_FAILURE() << what << ": pixel (" << ij.first << ", " << ij.second
                    << ") is not in the full frame";
      continue;
    }
    if (it->second != bits)
    {
      if (++differing <= 6)
        examples += "\n  (" + std::to_string(ij.first) + ", " + std::to_string(ij.second) +
                    "): " + asrt::testing::describeDifference(bits, it->second);
    }
  }
  EXPECT_EQ(differing, 0) << what << ": " << differing << " of " << records.size()
                          << " records differ from the full frame's (" << what
                          << " value first, then the full frame's):" << examples;
}
}

// ---------------------------------------------------------------------------------------------
// 1. What the ports hold.

TEST(GeodesicSource, ImagePortHasTheFrameAndItsArrays)
{
  const Frame& f = fig1Frame();
  ASSERT_TRUE(f.errors.empty()) << f.errors.front();
  int ext[6];
  f.image->GetExtent(ext);
  const int expected[6] = { 0, kW - 1, 0, kH - 1, 0, 0 };
  for (int k = 0; k < 6; ++k)
    EXPECT_EQ(ext[k], expected[k]) << "extent[" << k << "]";

  vtkDataArray* colors = f.image->GetPointData()->GetScalars();
  ASSERT_NE(colors, nullptr);
  EXPECT_STREQ(colors->GetName(), "Colors");
  EXPECT_EQ(colors->GetDataType(), VTK_UNSIGNED_CHAR);
  EXPECT_EQ(colors->GetNumberOfComponents(), 3);
  EXPECT_EQ(colors->GetNumberOfTuples(), kW * kH);
  for (const char* name : { "ObjectId", "ImageOrder", "PathLength", "Termination" })
  {
    vtkDataArray* a = f.image->GetPointData()->GetArray(name);
    ASSERT_NE(a, nullptr) << name;
    EXPECT_EQ(a->GetNumberOfComponents(), 1) << name;
    EXPECT_EQ(a->GetNumberOfTuples(), kW * kH) << name;
  }
}

TEST(GeodesicSource, HitsPortHasOneVertexAndRecordPerPixel)
{
  vtkPolyData* hits = fig1Frame().hits;
  ASSERT_EQ(hits->GetNumberOfPoints(), kW * kH);
  ASSERT_EQ(hits->GetNumberOfVerts(), kW * kH);
  EXPECT_EQ(hits->GetNumberOfCells(), kW * kH) << "only vertices expected";
  vtkNew<vtkIdList> ids;
  std::set<vtkIdType> used;
  for (vtkIdType c = 0; c < hits->GetNumberOfCells(); ++c)
  {
    hits->GetCellPoints(c, ids);
    ASSERT_EQ(ids->GetNumberOfIds(), 1);
    used.insert(ids->GetId(0));
  }
  EXPECT_EQ(used.size(), static_cast<size_t>(kW * kH)) << "a point without a vertex";

  const std::vector<std::pair<const char*, int>> arrays = {
    { "Pixel", 2 },       { "Origin", 3 },     { "Direction", 3 }, { "Momentum", 4 },
    { "Termination", 1 }, { "ObjectId", 1 },   { "HitNormal", 3 }, { "UV", 2 },
    { "ChordError", 1 },  { "PathLength", 1 }, { "Winding", 1 },   { "ImageOrder", 1 },
    { "Steps", 1 },       { "MaxAbsH", 1 },    { "Color", 3 },     { "Jacobian", 4 },
    { "Traced", 1 }
  };
  for (const auto& [name, components] : arrays)
  {
    vtkDataArray* a = hits->GetPointData()->GetArray(name);
    ASSERT_NE(a, nullptr) << name;
    EXPECT_EQ(a->GetNumberOfComponents(), components) << name;
    EXPECT_EQ(a->GetNumberOfTuples(), kW * kH) << name;
  }

  // Every pixel exactly once.
  const auto& records = fig1Records();
  EXPECT_EQ(records.size(), static_cast<size_t>(kW * kH));
  for (int j = 0; j < kH; ++j)
    for (int i = 0; i < kW; ++i)
      EXPECT_EQ(records.count({ i, j }), 1u) << "pixel (" << i << ", " << j << ")";

  // Every ray starts at the eye and was followed to a definite end: the scene is built so that
  // no ray runs out of steps or loses its Hamiltonian.
  vtkDataArray* origin = hits->GetPointData()->GetArray("Origin");
  vtkDataArray* term = hits->GetPointData()->GetArray("Termination");
  int undecided = 0;
  for (vtkIdType k = 0; k < hits->GetNumberOfPoints(); ++k)
  {
    EXPECT_EQ(origin->GetComponent(k, 0), 0.0);
    EXPECT_EQ(origin->GetComponent(k, 1), -30.0);
    EXPECT_EQ(origin->GetComponent(k, 2), 8.0);
    const int t = static_cast<int>(term->GetComponent(k, 0));
    if (t != 1 && t != 2 && t != 5) // Escaped, Captured, HitObject
      ++undecided;
  }
  EXPECT_EQ(undecided, 0) << "rays ending in Running, StepBudget or NumericalFailure";
}

TEST(GeodesicSource, HitsPortCarriesTheFrameParametersAsFieldData)
{
  vtkPolyData* hits = fig1Frame().hits;
  vtkFieldData* fd = hits->GetFieldData();
  for (const char* name :
       { "SceneJSON", "IntegrationMethod", "Mass", "Spin", "Charge", "CameraPosition", "FocalPoint",
         "ViewUp", "ViewAngle", "Resolution", "IntegrationStep", "Tolerances" })
    EXPECT_NE(fd->GetAbstractArray(name), nullptr) << name;

  const std::string json = fieldString(hits, "SceneJSON");
  EXPECT_NE(json.find("\"name\":\"Fig. 1: three cylinders crossing at a Schwarzschild hole\""),
            std::string::npos)
    << json.substr(0, 200);
  const std::string method = fieldString(hits, "IntegrationMethod");
  EXPECT_FALSE(method.empty());
  EXPECT_NE(method, "auto") << "the method actually used must be stored, not the request";

  EXPECT_EQ(fieldValue(hits, "Mass"), 1.0);
  EXPECT_EQ(fieldValue(hits, "Spin"), 0.0);
  EXPECT_EQ(fieldValue(hits, "Charge"), 0.0);
  const double position[3] = { 0, -30, 8 }, up[3] = { 0, 0, 1 };
  for (int c = 0; c < 3; ++c)
  {
    EXPECT_EQ(fieldValue(hits, "CameraPosition", c), position[c]);
    EXPECT_EQ(fieldValue(hits, "FocalPoint", c), 0.0);
    EXPECT_EQ(fieldValue(hits, "ViewUp", c), up[c]);
  }
  EXPECT_EQ(fieldValue(hits, "ViewAngle"), 30.0);
  EXPECT_EQ(fieldValue(hits, "Resolution", 0), kW) << "the override, not the scene's 200";
  EXPECT_EQ(fieldValue(hits, "Resolution", 1), kH);
  EXPECT_EQ(fieldValue(hits, "IntegrationStep"), 0.05);
  ASSERT_NE(fd->GetArray("Tolerances"), nullptr);
  EXPECT_EQ(fd->GetArray("Tolerances")->GetNumberOfComponents(), 2);
  EXPECT_GT(fieldValue(hits, "Tolerances", 0), 0.0);
  EXPECT_GT(fieldValue(hits, "Tolerances", 1), 0.0);
}

TEST(GeodesicSource, ImageAgreesWithTheRecordsPixelByPixel)
{
  const Frame& f = fig1Frame();
  vtkPointData* img = f.image->GetPointData();
  vtkPointData* rec = f.hits->GetPointData();
  vtkDataArray* pixel = rec->GetArray("Pixel");
  ASSERT_NE(pixel, nullptr);
  int objectIdMismatches = 0, otherMismatches = 0;
  std::set<int> objects;
  for (vtkIdType k = 0; k < f.hits->GetNumberOfPoints(); ++k)
  {
    const int i = static_cast<int>(pixel->GetComponent(k, 0));
    const int j = static_cast<int>(pixel->GetComponent(k, 1));
    const vtkIdType p = pointOf(f.image, i, j);
    ASSERT_GE(p, 0);
    const double id = rec->GetArray("ObjectId")->GetComponent(k, 0);
    objects.insert(static_cast<int>(id));
    if (img->GetArray("ObjectId")->GetComponent(p, 0) != id)
      ++objectIdMismatches;
    for (const char* name : { "Termination", "ImageOrder", "PathLength" })
      if (img->GetArray(name)->GetComponent(p, 0) != rec->GetArray(name)->GetComponent(k, 0))
        ++otherMismatches;
    for (int c = 0; c < 3; ++c)
    {
      const double expected =
        std::lround(255.0 * std::clamp(rec->GetArray("Color")->GetComponent(k, c), 0.0, 1.0));
      if (img->GetScalars()->GetComponent(p, c) != expected)
        ++otherMismatches;
    }
  }
  EXPECT_EQ(objectIdMismatches, 0);
  EXPECT_EQ(otherMismatches, 0);
  // A frame of this scene shows the sky, the hole and the cylinders (ids 0, −1, 1–3).
  for (int id : { -1, 0, 1, 2, 3 })
    EXPECT_EQ(objects.count(id), 1u) << "object " << id << " not seen in the frame";
}

// ---------------------------------------------------------------------------------------------
// 2. Overrides.

TEST(GeodesicSource, MassZeroOverrideGivesTheFlatSpaceFrame)
{
  const Frame flat = traceFrame(
    [](vtkGeodesicSource* s)
    {
      s->SetSceneFileName(scenePath("fig1-cylinders.json").c_str());
      s->SetResolution(kW, kH);
      s->SetMass(0.0);
    });
  const Frame fig2 = traceFrame(
    [](vtkGeodesicSource* s)
    {
      s->SetSceneFileName(scenePath("fig2-no-hole.json").c_str());
      s->SetResolution(kW, kH);
    });
  ASSERT_TRUE(flat.errors.empty()) << flat.errors.front();
  ASSERT_TRUE(fig2.errors.empty()) << fig2.errors.front();
  ASSERT_EQ(flat.image->GetNumberOfPoints(), kW * kH);
  ASSERT_EQ(fig2.image->GetNumberOfPoints(), kW * kH);
  int idDiff = 0, colorDiff = 0;
  for (vtkIdType p = 0; p < kW * kH; ++p)
  {
    if (flat.image->GetPointData()->GetArray("ObjectId")->GetComponent(p, 0) !=
        fig2.image->GetPointData()->GetArray("ObjectId")->GetComponent(p, 0))
      ++idDiff;
    for (int c = 0; c < 3; ++c)
      if (flat.image->GetPointData()->GetScalars()->GetComponent(p, c) !=
          fig2.image->GetPointData()->GetScalars()->GetComponent(p, c))
        ++colorDiff;
  }
  EXPECT_EQ(idDiff, 0) << "pixels whose object differs between Fig. 1 with M = 0 and Fig. 2";
  EXPECT_EQ(colorDiff, 0);
  // In flat space nothing is captured, and the mass-1 frame must differ (the override acted).
  vtkDataArray* term = flat.image->GetPointData()->GetArray("Termination");
  for (vtkIdType p = 0; p < kW * kH; ++p)
    ASSERT_NE(term->GetComponent(p, 0), 2.0) << "a ray captured in flat space";
  int differsFromMassOne = 0;
  for (vtkIdType p = 0; p < kW * kH; ++p)
    if (flat.image->GetPointData()->GetArray("ObjectId")->GetComponent(p, 0) !=
        fig1Frame().image->GetPointData()->GetArray("ObjectId")->GetComponent(p, 0))
      ++differsFromMassOne;
  EXPECT_GT(differsFromMassOne, kW * kH / 20);

  EXPECT_EQ(fieldValue(flat.hits, "Mass"), 0.0);
  EXPECT_EQ(fieldString(flat.hits, "IntegrationMethod"),
            fieldString(fig2.hits, "IntegrationMethod"))
    << "the method stored must be the one chosen for flat space";
}

TEST(GeodesicSource, FieldDataReflectEveryOverride)
{
  // One pixel is enough: the field data describe the frame, not the pixels.
  const Frame f = traceFrame(
    [](vtkGeodesicSource* s)
    {
      s->SetSceneFileName(scenePath("fig1-cylinders.json").c_str());
      s->SetMass(0.5);
      s->SetCameraPosition(0, -25, 5);
      s->SetFocalPoint(1, 0, 0);
      s->SetViewUp(0, 0.1, 1);
      s->SetViewAngle(40);
      s->SetResolution(24, 16);
      s->SetIntegrationMethod("GaussLegendre4");
      s->SetIntegrationStep(0.1);
      s->SetPixelSubset(pixelList({ { 12, 8 } }));
    });
  ASSERT_TRUE(f.errors.empty()) << f.errors.front();
  vtkPolyData* hits = f.hits;
  EXPECT_EQ(fieldValue(hits, "Mass"), 0.5);
  const double position[3] = { 0, -25, 5 }, focal[3] = { 1, 0, 0 }, up[3] = { 0, 0.1, 1 };
  for (int c = 0; c < 3; ++c)
  {
    EXPECT_EQ(fieldValue(hits, "CameraPosition", c), position[c]);
    EXPECT_EQ(fieldValue(hits, "FocalPoint", c), focal[c]);
    EXPECT_EQ(fieldValue(hits, "ViewUp", c), up[c]);
  }
  EXPECT_EQ(fieldValue(hits, "ViewAngle"), 40.0);
  EXPECT_EQ(fieldValue(hits, "Resolution", 0), 24.0);
  EXPECT_EQ(fieldValue(hits, "Resolution", 1), 16.0);
  EXPECT_EQ(fieldValue(hits, "IntegrationStep"), 0.1);
  EXPECT_EQ(fieldString(hits, "IntegrationMethod"), "GaussLegendre4");
  // The frame follows the overrides too: its extent and the ray's eye.
  int ext[6];
  f.image->GetExtent(ext);
  EXPECT_EQ(ext[1], 23);
  EXPECT_EQ(ext[3], 15);
  ASSERT_EQ(hits->GetNumberOfPoints(), 1);
  vtkDataArray* origin = hits->GetPointData()->GetArray("Origin");
  for (int c = 0; c < 3; ++c)
    EXPECT_EQ(origin->GetComponent(0, c), position[c]);
}

TEST(GeodesicSource, PresetReplacesTheIntegratorAndMethodStepRefineIt)
{
  // Presets are documented (Data/scenes/README.md) as rtol 1e-8, 1e-10, 1e-12 with atol = 1e-2
  // rtol for the method "auto" picks (PlanarOrbit for Schwarzschild); a method or step given beside
  // one refines it.
  const std::pair<const char*, double> presets[] = { { "fast", 1e-8 },
                                                     { "balanced", 1e-10 },
                                                     { "accurate", 1e-12 } };
  for (const auto& [name, rtol] : presets)
  {
    const Frame f = traceFrame(
      [name = name](vtkGeodesicSource* s)
      {
        s->SetSceneFileName(scenePath("fig1-cylinders.json").c_str());
        s->SetResolution(8, 8);
        s->SetPixelSubset(pixelList({ { 4, 4 } }));
        s->SetIntegrationPreset(name);
      });
    ASSERT_TRUE(f.errors.empty()) << f.errors.front();
    EXPECT_EQ(fieldString(f.hits, "IntegrationMethod"),
              asrt::defaultMethod(asrt::SchwarzschildSpacetime(1.0)))
      << name;
    EXPECT_DOUBLE_EQ(fieldValue(f.hits, "Tolerances", 0), rtol) << name;
    EXPECT_DOUBLE_EQ(fieldValue(f.hits, "Tolerances", 1), 1e-2 * rtol) << name;
  }
  const Frame refined = traceFrame(
    [](vtkGeodesicSource* s)
    {
      s->SetSceneFileName(scenePath("fig1-cylinders.json").c_str());
      s->SetResolution(8, 8);
      s->SetPixelSubset(pixelList({ { 4, 4 } }));
      s->SetIntegrationPreset("fast");
      s->SetIntegrationMethod("GaussLegendre4");
      s->SetIntegrationStep(0.2);
    });
  ASSERT_TRUE(refined.errors.empty()) << refined.errors.front();
  EXPECT_EQ(fieldString(refined.hits, "IntegrationMethod"), "GaussLegendre4");
  EXPECT_EQ(fieldValue(refined.hits, "IntegrationStep"), 0.2);
  EXPECT_DOUBLE_EQ(fieldValue(refined.hits, "Tolerances", 0), 1e-8);
}

TEST(GeodesicSource, ZeroResolutionKeepsTheScenes)
{
  vtkNew<vtkGeodesicSource> s;
  s->SetSceneFileName(scenePath("fig1-cylinders.json").c_str());
  s->SetResolution(0, 0);
  s->UpdateInformation();
  int ext[6];
  s->GetOutputInformation(0)->Get(vtkStreamingDemandDrivenPipeline::WHOLE_EXTENT(), ext);
  EXPECT_EQ(ext[1], 199);
  EXPECT_EQ(ext[3], 199);
}

TEST(GeodesicSource, NaNOverridesGiveTheScenesValuesBack)
{
  vtkNew<vtkGeodesicSource> s;
  s->SetSceneFileName(scenePath("fig1-cylinders.json").c_str());
  s->SetResolution(8, 8);
  s->SetPixelSubset(pixelList({ { 4, 4 } }));
  s->SetMass(0.5);
  s->SetViewAngle(20);
  s->SetCameraPosition(0, -20, 4);
  s->Update();
  ASSERT_EQ(fieldValue(s->GetHitsOutput(), "Mass"), 0.5);
  s->SetMass(kNaN);
  s->SetViewAngle(kNaN);
  s->SetCameraPosition(kNaN, kNaN, kNaN);
  s->Update();
  EXPECT_EQ(fieldValue(s->GetHitsOutput(), "Mass"), 1.0);
  EXPECT_EQ(fieldValue(s->GetHitsOutput(), "ViewAngle"), 30.0);
  EXPECT_EQ(fieldValue(s->GetHitsOutput(), "CameraPosition", 1), -30.0);
}

TEST(GeodesicSource, RecordsDoNotDependOnTheNumberOfThreads)
{
  // The header promises identical results for any number of OpenMP threads; the reference ran
  // with the default (2 here), this run with one.
  const int before = omp_get_max_threads();
  omp_set_num_threads(1);
  const Frame single = traceFrame(
    [](vtkGeodesicSource* s)
    {
      s->SetSceneFileName(scenePath("fig1-cylinders.json").c_str());
      s->SetResolution(kW, kH);
    });
  omp_set_num_threads(before);
  ASSERT_TRUE(single.errors.empty()) << single.errors.front();
  const auto records = recordsByPixel(single.hits);
  EXPECT_EQ(records.size(), static_cast<size_t>(kW * kH));
  expectRecordsMatchReference(records, "one thread");
}

// ---------------------------------------------------------------------------------------------
// 3. Pieces.

TEST(GeodesicSource, PiecesTogetherEqualTheWholeFrame)
{
  vtkNew<vtkGeodesicSource> s;
  vtkNew<MessageCatcher> catcher;
  asrt::testing::watch(s, catcher);
  s->SetSceneFileName(scenePath("fig1-cylinders.json").c_str());
  s->SetResolution(kW, kH);
  const int n = 3;
  std::map<Pixel, RecordBits> all;
  const Frame& full = fig1Frame();
  for (int p = 0; p < n; ++p)
  {
    SCOPED_TRACE("piece " + std::to_string(p));
    ASSERT_TRUE(s->UpdatePiece(p, n, 0));
    ASSERT_TRUE(catcher->Errors.empty()) << catcher->AllErrors();
    // Pieces are documented as bands of whole rows; this is the split a reader would expect.
    const int rowBegin = kH * p / n, rowEnd = kH * (p + 1) / n;
    vtkImageData* image = s->GetImageOutput();
    int ext[6];
    image->GetExtent(ext);
    EXPECT_EQ(ext[0], 0);
    EXPECT_EQ(ext[1], kW - 1);
    EXPECT_LE(ext[2], rowBegin);
    EXPECT_GE(ext[3], rowEnd - 1);
    const auto records = recordsByPixel(s->GetHitsOutput());
    EXPECT_EQ(records.size(), static_cast<size_t>(kW * (rowEnd - rowBegin)));
    for (const auto& [ij, bits] : records)
    {
      EXPECT_TRUE(ij.second >= rowBegin && ij.second < rowEnd)
        << "record of row " << ij.second << " outside the piece's band";
      if (!all.emplace(ij, bits).second)
        ADD_FAILURE() << "pixel (" << ij.first << ", " << ij.second << ") in two pieces";
      // The piece's image shows the same pixel as the whole frame's.
      const vtkIdType q = pointOf(image, ij.first, ij.second);
      const vtkIdType r = pointOf(full.image, ij.first, ij.second);
      ASSERT_GE(q, 0) << "pixel outside the piece's image";
      for (const char* name : { "ObjectId", "Termination", "ImageOrder", "PathLength" })
        EXPECT_EQ(image->GetPointData()->GetArray(name)->GetComponent(q, 0),
                  full.image->GetPointData()->GetArray(name)->GetComponent(r, 0))
          << name << " at (" << ij.first << ", " << ij.second << ")";
    }
  }
  EXPECT_EQ(all.size(), fig1Records().size());
  expectRecordsMatchReference(all, "union of 3 pieces");
}

// ---------------------------------------------------------------------------------------------
// 4. Pixel subsets.

TEST(GeodesicSource, PixelSubsetTracesOnlyThosePixelsAndMatchesTheFullFrame)
{
  // Corners, the centre, a run of neighbours along a row and a pair along a column.
  const std::vector<Pixel> subset = { { 0, 0 },  { 31, 31 }, { 16, 16 }, { 5, 20 }, { 6, 20 },
                                      { 7, 20 }, { 12, 3 },  { 12, 4 },  { 25, 9 }, { 0, 31 } };
  const Frame f = traceFrame(
    [&](vtkGeodesicSource* s)
    {
      s->SetSceneFileName(scenePath("fig1-cylinders.json").c_str());
      s->SetResolution(kW, kH);
      s->SetPixelSubset(pixelList(subset));
    });
  ASSERT_TRUE(f.errors.empty()) << f.errors.front();
  ASSERT_EQ(f.image->GetNumberOfPoints(), kW * kH) << "the image still covers the whole frame";
  const std::set<Pixel> chosen(subset.begin(), subset.end());
  vtkPointData* img = f.image->GetPointData();
  vtkPointData* ref = fig1Frame().image->GetPointData();
  for (int j = 0; j < kH; ++j)
    for (int i = 0; i < kW; ++i)
    {
      const vtkIdType p = pointOf(f.image, i, j);
      const double t = img->GetArray("Termination")->GetComponent(p, 0);
      if (chosen.count({ i, j }))
      {
        EXPECT_EQ(t, ref->GetArray("Termination")->GetComponent(p, 0)) << i << ", " << j;
        EXPECT_EQ(img->GetArray("ObjectId")->GetComponent(p, 0),
                  ref->GetArray("ObjectId")->GetComponent(p, 0))
          << i << ", " << j;
      }
      else
      {
        EXPECT_EQ(t, 0.0) << "untraced pixel (" << i << ", " << j << ") not Running";
        EXPECT_EQ(img->GetArray("ObjectId")->GetComponent(p, 0), -1.0);
        for (int c = 0; c < 3; ++c)
          EXPECT_EQ(img->GetScalars()->GetComponent(p, c), 0.0);
      }
    }
  const auto records = recordsByPixel(f.hits);
  EXPECT_EQ(records.size(), subset.size());
  for (const Pixel& ij : subset)
    EXPECT_EQ(records.count(ij), 1u) << ij.first << ", " << ij.second;
  // The subset's neighbours are traced too (and dropped), so that every record, Jacobians and
  // anti-aliased colour included, is the full frame's bit for bit, even at a corner pixel traced
  // alone.
  const auto& full = fig1Records();
  for (const auto& [ij, bits] : records)
    EXPECT_EQ(bits, full.at(ij)) << ij.first << ", " << ij.second;
  const RecordBits& corner = records.at({ 0, 0 });
  const size_t n = corner.size();
  for (size_t c = n - 4; c < n; ++c)
    EXPECT_FALSE(std::isnan(asrt::testing::asDouble(corner[c])))
      << "Jacobian component " << c - (n - 4);
}

// ---------------------------------------------------------------------------------------------
// 5. Polylines.

namespace
{
/// Checks port 2 against the reference frame: one line per chosen pixel, in order, from the eye
/// to the pixel's recorded end, with increasing λ, outside the horizon and on the light cone. The
/// line is traced again with every segment on the ray, while the frame's record may have crossed
/// the far field in one segment (FarField): the two agree to the tracing tolerance, not bit for
/// bit.
void checkPolylines(vtkPolyData* lines, const std::vector<Pixel>& chosen)
{
  const double rPlus = 2.0; // Schwarzschild, M = 1
  vtkPolyData* ref = fig1Frame().hits;
  std::map<Pixel, vtkIdType> refIndex;
  vtkDataArray* refPixel = ref->GetPointData()->GetArray("Pixel");
  for (vtkIdType k = 0; k < ref->GetNumberOfPoints(); ++k)
    refIndex[{ static_cast<int>(refPixel->GetComponent(k, 0)),
               static_cast<int>(refPixel->GetComponent(k, 1)) }] = k;
  const double eye[3] = { fieldValue(ref, "CameraPosition", 0),
                          fieldValue(ref, "CameraPosition", 1),
                          fieldValue(ref, "CameraPosition", 2) };

  ASSERT_EQ(lines->GetNumberOfLines(), static_cast<vtkIdType>(chosen.size()));
  ASSERT_EQ(lines->GetNumberOfCells(), static_cast<vtkIdType>(chosen.size()));
  vtkDataArray* lambda = lines->GetPointData()->GetArray("Lambda");
  vtkDataArray* radius = lines->GetPointData()->GetArray("R");
  vtkDataArray* absH = lines->GetPointData()->GetArray("AbsH");
  vtkDataArray* linePixel = lines->GetCellData()->GetArray("Pixel");
  vtkDataArray* lineTerm = lines->GetCellData()->GetArray("Termination");
  ASSERT_TRUE(lambda && radius && absH && linePixel && lineTerm);
  ASSERT_EQ(lambda->GetNumberOfTuples(), lines->GetNumberOfPoints());

  vtkNew<vtkIdList> ids;
  for (vtkIdType c = 0; c < lines->GetNumberOfCells(); ++c)
  {
    const Pixel ij(static_cast<int>(linePixel->GetComponent(c, 0)),
                   static_cast<int>(linePixel->GetComponent(c, 1)));
    SCOPED_TRACE("line of pixel (" + std::to_string(ij.first) + ", " + std::to_string(ij.second) +
                 ")");
    EXPECT_EQ(ij, chosen[c]) << "lines out of the requested order";
    const vtkIdType k = refIndex.at(ij);
    lines->GetCellPoints(c, ids);
    ASSERT_GE(ids->GetNumberOfIds(), 2);
    double first[3], last[3], hit[3];
    lines->GetPoint(ids->GetId(0), first);
    lines->GetPoint(ids->GetId(ids->GetNumberOfIds() - 1), last);
    ref->GetPoint(k, hit);
    // The polyline is traced without the far field and the record with it (FrameTracer), and a
    // propagator may step the two differently (PlanarSeries hands the far field to PlanarOrbit):
    // they agree to the balanced preset's accuracy, far below anything a picture shows.
    for (int d = 0; d < 3; ++d)
    {
      EXPECT_EQ(first[d], eye[d]) << "does not start at the eye";
      EXPECT_NEAR(last[d], hit[d], 1e-7 * (1 + std::abs(hit[d])))
        << "does not end at the record's hit point";
    }
    EXPECT_EQ(lineTerm->GetComponent(c, 0),
              ref->GetPointData()->GetArray("Termination")->GetComponent(k, 0));
    const double pathLength = ref->GetPointData()->GetArray("PathLength")->GetComponent(k, 0);
    EXPECT_NEAR(lambda->GetComponent(ids->GetId(ids->GetNumberOfIds() - 1), 0), pathLength,
                1e-8 * pathLength)
      << "λ at the end is not the record's path length";
    EXPECT_EQ(lambda->GetComponent(ids->GetId(0), 0), 0.0);
    const double maxAbsH = ref->GetPointData()->GetArray("MaxAbsH")->GetComponent(k, 0);
    int notIncreasing = 0, inside = 0, hTooLarge = 0;
    for (vtkIdType m = 0; m < ids->GetNumberOfIds(); ++m)
    {
      const vtkIdType q = ids->GetId(m);
      if (m > 0 && !(lambda->GetComponent(q, 0) > lambda->GetComponent(ids->GetId(m - 1), 0)))
        ++notIncreasing;
      if (!(radius->GetComponent(q, 0) >= rPlus))
        ++inside;
      if (!(absH->GetComponent(q, 0) <= 1e-6))
        ++hTooLarge;
    }
    EXPECT_EQ(notIncreasing, 0) << "of " << ids->GetNumberOfIds() << " points";
    EXPECT_EQ(inside, 0) << "points with R below the horizon r+ = " << rPlus;
    EXPECT_EQ(hTooLarge, 0) << "points off the light cone, |H| > 1e-6 (the record's MaxAbsH is "
                            << maxAbsH << ")";
    EXPECT_LT(maxAbsH, 1e-3) << "the tracing tolerance";
    // R is the distance from the hole in this chart: at the eye, |(0, −30, 8)|.
    EXPECT_NEAR(radius->GetComponent(ids->GetId(0), 0), std::sqrt(30.0 * 30.0 + 8.0 * 8.0), 1e-9);
  }
}
}

TEST(GeodesicSource, PolylinesWithAStride)
{
  const int stride = 8;
  std::vector<Pixel> chosen;
  for (int j = 0; j < kH; j += stride)
    for (int i = 0; i < kW; i += stride)
      chosen.emplace_back(i, j);
  vtkNew<vtkGeodesicSource> s;
  vtkNew<MessageCatcher> catcher;
  asrt::testing::watch(s, catcher);
  s->SetSceneFileName(scenePath("fig1-cylinders.json").c_str());
  s->SetResolution(kW, kH);
  s->SetPixelSubset(pixelList(chosen)); // the frame itself is not what this test is about
  s->GeneratePolylinesOn();
  s->SetPolylineStride(stride);
  s->Update();
  ASSERT_TRUE(catcher->Errors.empty()) << catcher->AllErrors();
  checkPolylines(s->GetPolylinesOutput(), chosen);
}

TEST(GeodesicSource, PolylinesOfExplicitPixels)
{
  const std::vector<Pixel> chosen = { { 3, 5 }, { 16, 16 }, { 31, 0 }, { 0, 31 }, { 20, 17 } };
  vtkNew<vtkGeodesicSource> s;
  vtkNew<MessageCatcher> catcher;
  asrt::testing::watch(s, catcher);
  s->SetSceneFileName(scenePath("fig1-cylinders.json").c_str());
  s->SetResolution(kW, kH);
  s->SetPixelSubset(pixelList(chosen));
  s->GeneratePolylinesOn();
  s->SetPolylinePixels(pixelList(chosen));
  s->Update();
  ASSERT_TRUE(catcher->Errors.empty()) << catcher->AllErrors();
  checkPolylines(s->GetPolylinesOutput(), chosen);
}

// The same list given a pixel at a time (ParaView's repeated property): the same polylines, and
// clearing it goes back to the stride; the caller's own array is never appended to.
TEST(GeodesicSource, PolylinePixelsAddedOneAtATime)
{
  const std::vector<Pixel> chosen = { { 3, 5 }, { 16, 16 }, { 31, 0 } };
  vtkNew<vtkGeodesicSource> s;
  vtkNew<MessageCatcher> catcher;
  asrt::testing::watch(s, catcher);
  s->SetSceneFileName(scenePath("fig1-cylinders.json").c_str());
  s->SetResolution(kW, kH);
  s->SetPixelSubset(pixelList(chosen));
  s->GeneratePolylinesOn();
  auto given = pixelList({ chosen[0] });
  s->SetPolylinePixels(given);
  for (std::size_t k = 1; k < chosen.size(); ++k)
    s->AddPolylinePixel(chosen[k].first, chosen[k].second);
  EXPECT_EQ(given->GetNumberOfTuples(), 1) << "the caller's array was appended to";
  s->Update();
  ASSERT_TRUE(catcher->Errors.empty()) << catcher->AllErrors();
  checkPolylines(s->GetPolylinesOutput(), chosen);

  s->ClearPolylinePixels();
  EXPECT_EQ(s->GetPolylinePixels(), nullptr);
  s->SetPolylineStride(16);
  s->SetPixelSubset(pixelList({ { 0, 0 }, { 16, 0 }, { 0, 16 }, { 16, 16 } }));
  s->Update();
  ASSERT_TRUE(catcher->Errors.empty()) << catcher->AllErrors();
  checkPolylines(s->GetPolylinesOutput(), { { 0, 0 }, { 16, 0 }, { 0, 16 }, { 16, 16 } });
}

// With an override switch off, its values are ignored and the scene's are traced (front ends
// whose properties cannot hold NaN); on (the default), they replace the scene's.
TEST(GeodesicSource, OverrideSwitchesDecideWhetherValuesApply)
{
  auto traced = [](bool switchesOn)
  {
    vtkNew<vtkGeodesicSource> s;
    s->SetSceneFileName(scenePath("kerr-disk.json").c_str());
    s->SetResolution(8, 6);
    s->SetPixelSubset(pixelList({ { 4, 3 } }));
    s->SetMass(0.5);
    s->SetSpin(0.1);
    s->SetCameraPosition(0, -20, 0);
    s->SetViewAngle(10);
    s->SetOverrideSpacetime(switchesOn);
    s->SetOverrideCamera(switchesOn);
    s->Update();
    vtkFieldData* fd = s->GetHitsOutput()->GetFieldData();
    const auto value = [fd](const char* name, int component)
    { return fd->GetArray(name) ? fd->GetArray(name)->GetComponent(0, component) : -1.0; };
    return std::vector<double>{ value("Mass", 0), value("Spin", 0), value("CameraPosition", 1),
                                value("ViewAngle", 0) };
  };
  // kerr-disk.json: M = 1, a = 0.9, the eye at y = −38.637…, a view angle of 45°.
  const std::vector<double> off = traced(false);
  EXPECT_EQ(off[0], 1.0);
  EXPECT_EQ(off[1], 0.9);
  EXPECT_NEAR(off[2], -38.63703305156273, 1e-12);
  EXPECT_EQ(off[3], 45.0);
  EXPECT_EQ(traced(true), (std::vector<double>{ 0.5, 0.1, -20.0, 10.0 }));
}

TEST(GeodesicSource, NoPolylinesUnlessAskedFor)
{
  EXPECT_EQ(fig1Frame().hits->GetNumberOfLines(), 0);
  vtkNew<vtkGeodesicSource> s;
  s->SetSceneFileName(scenePath("fig1-cylinders.json").c_str());
  s->SetResolution(kW, kH);
  s->SetPixelSubset(pixelList({ { 1, 1 } }));
  s->Update();
  EXPECT_EQ(s->GetPolylinesOutput()->GetNumberOfCells(), 0);
}

// ---------------------------------------------------------------------------------------------
// 6. Progress and abort.

TEST(GeodesicSource, ProgressIncreasesToOne)
{
  const std::vector<double>& v = fig1Frame().progress;
  ASSERT_GE(v.size(), 3u);
  for (size_t k = 1; k < v.size(); ++k)
    EXPECT_GE(v[k], v[k - 1]) << "progress went back at event " << k;
  for (double x : v)
  {
    EXPECT_GE(x, 0.0);
    EXPECT_LE(x, 1.0);
  }
  EXPECT_EQ(v.back(), 1.0);
  // Progress is reported during the trace, not only at its ends.
  const auto during = std::count_if(v.begin(), v.end(), [](double x) { return x > 0 && x < 1; });
  EXPECT_GE(during, 5);
}

TEST(GeodesicSource, AbortStopsEarlyAndALaterUpdateWorks)
{
  const int w = 96, h = 96;
  vtkNew<vtkGeodesicSource> s;
  vtkNew<MessageCatcher> catcher;
  asrt::testing::watch(s, catcher);
  s->SetSceneFileName(scenePath("fig1-cylinders.json").c_str());
  s->SetResolution(w, h);
  vtkNew<AbortAtFirstProgress> abort;
  const unsigned long tag = s->AddObserver(vtkCommand::ProgressEvent, abort);
  s->Update();
  EXPECT_GE(abort->Events, 1);
  // Stopping early is judged by the work reported done, not by wall-clock time (this machine is
  // shared): the tracer reports its fraction of pixels done, and must stop far short of all.
  EXPECT_LT(abort->Largest, 0.5) << "the aborted run went on to " << abort->Largest;
  EXPECT_EQ(s->GetImageOutput()->GetNumberOfPoints(), 0);
  EXPECT_EQ(s->GetHitsOutput()->GetNumberOfPoints(), 0);
  EXPECT_EQ(s->GetPolylinesOutput()->GetNumberOfPoints(), 0);
  EXPECT_TRUE(catcher->Errors.empty()) << "an abort is not an error: " << catcher->AllErrors();

  s->RemoveObserver(tag);
  s->SetAbortExecute(0);
  s->Update();
  EXPECT_TRUE(catcher->Errors.empty()) << catcher->AllErrors();
  ASSERT_EQ(s->GetImageOutput()->GetNumberOfPoints(), w * h);
  const auto records = recordsByPixel(s->GetHitsOutput());
  EXPECT_EQ(records.size(), static_cast<size_t>(w * h));
  vtkDataArray* term = s->GetImageOutput()->GetPointData()->GetArray("Termination");
  int untraced = 0;
  for (vtkIdType p = 0; p < w * h; ++p)
    if (term->GetComponent(p, 0) == 0.0)
      ++untraced;
  EXPECT_EQ(untraced, 0) << "pixels left Running after the repeated Update";

  // Back at the reference resolution the records are the reference's: nothing of the aborted
  // run lingers.
  s->SetResolution(kW, kH);
  s->Update();
  expectRecordsMatchReference(recordsByPixel(s->GetHitsOutput()), "after an abort");
}

// ---------------------------------------------------------------------------------------------
// 7. Bad input.

namespace
{
const char* const kSceneHead = R"({
  "spacetime": {"mass": 1},
  "camera": {"position": [0, -30, 8], "focalPoint": [0, 0, 0], "resolution": [8, 8]},
  "objects": [)";

std::string sceneWithObjects(const std::string& objects)
{
  return std::string(kSceneHead) + objects + "]}";
}

/// Runs the filter on a valid 8 × 8 Fig. 1 first, so that "empty after the error" means the
/// error cleared an earlier result; then breaks it, checks the error, repairs it and checks that
/// it works again.
void expectCleanError(const std::function<void(vtkGeodesicSource*)>& breakIt,
                      const std::function<void(vtkGeodesicSource*)>& repair,
                      const std::vector<std::string>& mentions, double maxSeconds = 30.0)
{
  vtkNew<vtkGeodesicSource> s;
  vtkNew<MessageCatcher> filterErrors;
  vtkNew<MessageCatcher> executiveErrors;
  s->AddObserver(vtkCommand::ErrorEvent, filterErrors);
  s->AddObserver(vtkCommand::WarningEvent, filterErrors);
  s->GetExecutive()->AddObserver(vtkCommand::ErrorEvent, executiveErrors);
  s->GetExecutive()->AddObserver(vtkCommand::WarningEvent, executiveErrors);
  s->SetSceneFileName(scenePath("fig1-cylinders.json").c_str());
  s->SetResolution(8, 8);
  s->Update();
  ASSERT_TRUE(filterErrors->Errors.empty()) << filterErrors->AllErrors();
  ASSERT_EQ(s->GetImageOutput()->GetNumberOfPoints(), 64);

  breakIt(s);
  const auto t0 = std::chrono::steady_clock::now();
  s->Update();
  const double seconds = secondsSince(t0);
  EXPECT_LT(seconds,
            maxSeconds); // a guard against hangs (and allocating first), not a speed target
  ASSERT_FALSE(filterErrors->Errors.empty()) << "no error reported by the filter itself";
  for (const std::string& m : mentions)
    EXPECT_TRUE(filterErrors->Mentions(m))
      << "the error does not mention \"" << m << "\": " << filterErrors->AllErrors();
  EXPECT_EQ(s->GetImageOutput()->GetNumberOfPoints(), 0)
    << "image output not emptied (error: " << filterErrors->Errors.front() << ")";
  EXPECT_EQ(s->GetHitsOutput()->GetNumberOfPoints(), 0)
    << "hits output not emptied (error: " << filterErrors->Errors.front() << ")";
  EXPECT_EQ(s->GetPolylinesOutput()->GetNumberOfPoints(), 0);

  filterErrors->Clear();
  executiveErrors->Clear();
  repair(s);
  s->Update();
  EXPECT_TRUE(filterErrors->Errors.empty()) << filterErrors->AllErrors();
  EXPECT_TRUE(executiveErrors->Errors.empty()) << executiveErrors->AllErrors();
  EXPECT_EQ(s->GetImageOutput()->GetNumberOfPoints(), 64);
  EXPECT_EQ(s->GetHitsOutput()->GetNumberOfPoints(), 64);
}
}

TEST(GeodesicSourceErrors, MissingTextureFile)
{
  expectCleanError(
    [](vtkGeodesicSource* s)
    {
      s->SetSceneText(sceneWithObjects(R"({"type": "sphere", "id": 1, "center": [0, 10, 0],
        "radius": 2, "texture": {"image": "no-such-texture-4711.png"}})")
                        .c_str());
    },
    [](vtkGeodesicSource* s) { s->SetSceneText(nullptr); }, { "no-such-texture-4711.png" });
}

TEST(GeodesicSourceErrors, CameraInsideTheHorizon)
{
  expectCleanError([](vtkGeodesicSource* s) { s->SetCameraPosition(0, -1, 0); },
                   [](vtkGeodesicSource* s) { s->SetCameraPosition(kNaN, kNaN, kNaN); },
                   { "horizon" });
}

TEST(GeodesicSourceErrors, CameraPositionOnlyPartlyGiven)
{
  // NaN means "keep the scene's value" for a whole vector; a half-NaN position is no position.
  expectCleanError([](vtkGeodesicSource* s) { s->SetCameraPosition(0, -30, kNaN); },
                   [](vtkGeodesicSource* s) { s->SetCameraPosition(kNaN, kNaN, kNaN); },
                   { "position" });
}

TEST(GeodesicSourceErrors, NegativeViewAngle)
{
  expectCleanError([](vtkGeodesicSource* s) { s->SetViewAngle(-5); },
                   [](vtkGeodesicSource* s) { s->SetViewAngle(kNaN); }, { "viewAngle", "-5" });
}

TEST(GeodesicSourceErrors, MassGivenAsAString)
{
  expectCleanError(
    [](vtkGeodesicSource* s)
    {
      s->SetSceneText(R"({"spacetime": {"mass": "nan"},
        "camera": {"position": [0, -30, 8], "focalPoint": [0, 0, 0]}, "objects": []})");
    },
    [](vtkGeodesicSource* s) { s->SetSceneText(nullptr); }, { "mass" });
}

TEST(GeodesicSourceErrors, OneZeroResolution)
{
  expectCleanError([](vtkGeodesicSource* s) { s->SetResolution(0, 10); },
                   [](vtkGeodesicSource* s) { s->SetResolution(8, 8); }, { "resolution" });
}

TEST(GeodesicSourceErrors, AbsurdResolutionIsRefusedBeforeAllocating)
{
  // 4·10¹⁰ pixels: any attempt to allocate would take far longer than a second, or fail.
  expectCleanError([](vtkGeodesicSource* s) { s->SetResolution(200000, 200000); },
                   [](vtkGeodesicSource* s) { s->SetResolution(8, 8); }, { "200000 x 200000" },
                   1.0);
}

TEST(GeodesicSourceErrors, AbsurdResolutionMessageNamesTheCost)
{
  vtkNew<vtkGeodesicSource> s;
  vtkNew<MessageCatcher> catcher;
  asrt::testing::watch(s, catcher);
  s->SetSceneFileName(scenePath("fig1-cylinders.json").c_str());
  s->SetResolution(200000, 200000);
  s->Update();
  EXPECT_TRUE(catcher->Mentions("GB") || catcher->Mentions("memory") || catcher->Mentions("pixels"))
    << catcher->AllErrors();
}

TEST(GeodesicSourceErrors, UnknownObjectType)
{
  expectCleanError(
    [](vtkGeodesicSource* s)
    {
      s->SetSceneText(
        sceneWithObjects(R"({"type": "torus", "id": 1, "center": [0, 0, 0]})").c_str());
    },
    [](vtkGeodesicSource* s) { s->SetSceneText(nullptr); }, { "torus" });
}

TEST(GeodesicSourceErrors, NoScene)
{
  expectCleanError([](vtkGeodesicSource* s) { s->SetSceneFileName(nullptr); },
                   [](vtkGeodesicSource* s)
                   { s->SetSceneFileName(scenePath("fig1-cylinders.json").c_str()); },
                   { "scene" });
}

TEST(GeodesicSourceErrors, NoSceneOnAFreshFilter)
{
  vtkNew<vtkGeodesicSource> s;
  vtkNew<MessageCatcher> catcher;
  asrt::testing::watch(s, catcher);
  s->Update();
  EXPECT_TRUE(catcher->Mentions("no scene")) << catcher->AllErrors();
  EXPECT_EQ(s->GetImageOutput()->GetNumberOfPoints(), 0);
  EXPECT_EQ(s->GetHitsOutput()->GetNumberOfPoints(), 0);
}

TEST(GeodesicSourceErrors, PixelSubsetEntryOutsideTheFrame)
{
  expectCleanError(
    [](vtkGeodesicSource* s) {
      s->SetPixelSubset(pixelList({ { 2, 3 }, { 8, 1 } }));
    },
    [](vtkGeodesicSource* s) { s->SetPixelSubset(nullptr); }, { "outside", "(8, 1)" });
}

TEST(GeodesicSourceErrors, UnknownIntegrationMethod)
{
  expectCleanError([](vtkGeodesicSource* s) { s->SetIntegrationMethod("RungeKuttaNonsense"); },
                   [](vtkGeodesicSource* s) { s->SetIntegrationMethod(""); },
                   { "RungeKuttaNonsense" });
}

TEST(GeodesicSourceErrors, UnknownPreset)
{
  expectCleanError([](vtkGeodesicSource* s) { s->SetIntegrationPreset("fastest"); },
                   [](vtkGeodesicSource* s) { s->SetIntegrationPreset(nullptr); }, { "fastest" });
}

TEST(GeodesicSourceErrors, MissingSceneFile)
{
  expectCleanError(
    [](vtkGeodesicSource* s) { s->SetSceneFileName(scenePath("no-such-scene.json").c_str()); },
    [](vtkGeodesicSource* s) { s->SetSceneFileName(scenePath("fig1-cylinders.json").c_str()); },
    { "no-such-scene.json" });
}

TEST(GeodesicSourceErrors, InfiniteMass)
{
  expectCleanError([](vtkGeodesicSource* s)
                   { s->SetMass(std::numeric_limits<double>::infinity()); },
                   [](vtkGeodesicSource* s) { s->SetMass(kNaN); }, { "mass" });
}

TEST(GeodesicSourceErrors, PixelSubsetWithThreeComponents)
{
  // The subset is documented as a 2-component array of (i, j). An array of another shape is
  // read as if it had two components; with one component that reads past the array's end.
  expectCleanError(
    [](vtkGeodesicSource* s)
    {
      vtkNew<vtkIntArray> ijk;
      ijk->SetNumberOfComponents(3);
      const int t[3] = { 1, 2, 0 };
      ijk->InsertNextTypedTuple(t);
      s->SetPixelSubset(ijk);
    },
    [](vtkGeodesicSource* s) { s->SetPixelSubset(nullptr); }, { "component" });
}

TEST(GeodesicSource, WithoutHitPointsTheImageIsTheSame)
{
  // GenerateHitPoints off: the hits output keeps the frame's field data but no point, and the
  // image's every array equals the one traced with the hit points, value for value.
  auto configure = [](bool hits)
  {
    return [hits](vtkGeodesicSource* s)
    {
      s->SetSceneFileName(scenePath("fig1-cylinders.json").c_str());
      s->SetResolution(40, 30);
      s->SetGenerateHitPoints(hits);
    };
  };
  const Frame with = traceFrame(configure(true));
  const Frame without = traceFrame(configure(false));
  ASSERT_TRUE(with.errors.empty() && without.errors.empty());
  EXPECT_EQ(with.hits->GetNumberOfPoints(), 40 * 30);
  EXPECT_EQ(without.hits->GetNumberOfPoints(), 0);
  EXPECT_EQ(fieldValue(without.hits, "Resolution", 0), 40.0);
  vtkPointData* a = with.image->GetPointData();
  vtkPointData* b = without.image->GetPointData();
  ASSERT_EQ(a->GetNumberOfArrays(), b->GetNumberOfArrays());
  for (int k = 0; k < a->GetNumberOfArrays(); ++k)
  {
    vtkDataArray* x = a->GetArray(k);
    vtkDataArray* y = b->GetArray(x->GetName());
    ASSERT_NE(y, nullptr) << x->GetName();
    ASSERT_EQ(x->GetNumberOfTuples(), y->GetNumberOfTuples()) << x->GetName();
    ASSERT_EQ(x->GetNumberOfComponents(), y->GetNumberOfComponents()) << x->GetName();
    for (vtkIdType t = 0; t < x->GetNumberOfTuples(); ++t)
      for (int c = 0; c < x->GetNumberOfComponents(); ++c)
        ASSERT_EQ(x->GetComponent(t, c), y->GetComponent(t, c)) << x->GetName() << " " << t;
  }
  EXPECT_STREQ(b->GetScalars()->GetName(), "Colors");
}
