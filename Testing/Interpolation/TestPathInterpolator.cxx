// vtkGeodesicPathInterpolator against frames traced by vtkGeodesicSource at the interpolated
// parameters: the mass ramp of Figs. 4–5 through four key frames, and an orbit of Fig. 1.
#include "InterpolationTestSupport.h"
#include "vtkGeodesicPathInterpolator.h"

#include "GeodesicRecordArrays.h"
#include "KdTreeIndex.h"
#include "PathInterpolation.h"
#include "RampScene.h"
#include "Spacetime.h"

#include "vtkIdTypeArray.h"
#include "vtkInformation.h"
#include "vtkIntArray.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <string>
#include <vector>

using namespace asrt::testing;

namespace
{
constexpr int kSide = 80;

std::string textureDirectory()
{
  return std::string(ASRT_SOURCE_DIR) + "/Data/scenes";
}

const TracedFrame& rampKey(double mass)
{
  static std::map<double, TracedFrame> frames;
  auto it = frames.find(mass);
  if (it == frames.end())
    it = frames
           .emplace(mass, traceWith(
                            [mass](vtkGeodesicSource* s)
                            {
                              s->SetSceneFileName(scenePath("fig4-mass-start.json").c_str());
                              s->SetResolution(kSide, kSide);
                              s->SetMass(mass);
                            }))
           .first;
  return it->second;
}

struct Pipeline
{
  std::vector<vtkSmartPointer<vtkTrivialProducer>> producers;
  vtkNew<vtkGeodesicPathInterpolator> interpolator;
  vtkNew<MessageCatcher> catcher;

  explicit Pipeline(const std::vector<vtkPolyData*>& keys)
  {
    watch(this->interpolator, this->catcher);
    for (vtkPolyData* k : keys)
    {
      this->producers.push_back(producerOf(k));
      this->interpolator->AddKeyFrameConnection(this->producers.back()->GetOutputPort());
    }
    this->interpolator->SetTextureDirectory(textureDirectory().c_str());
  }
  vtkImageData* at(double time)
  {
    this->interpolator->UpdateTimeStep(time);
    return this->interpolator->GetOutput();
  }
};

/// The ramp's frame at M = 0.72 (time 1.4 between the keys 0.65 … 0.8), traced with the scene's
/// rendering (supersample 1) or with supersample × supersample filtered samples in every pixel.
TracedFrame tracedAt072(int supersample)
{
  return traceWith(
    [supersample](vtkGeodesicSource* s)
    {
      s->SetSceneFileName(scenePath("fig4-mass-start.json").c_str());
      s->SetResolution(kSide, kSide);
      s->SetMass(0.72);
      if (supersample > 1)
      {
        s->SetAntialias("filter");
        s->SetSupersample(supersample);
        s->SetGridLattice(1);
      }
    });
}

std::vector<vtkPolyData*> rampKeys(const std::vector<double>& masses)
{
  std::vector<vtkPolyData*> keys;
  for (double m : masses)
    keys.push_back(rampKey(m).hits);
  return keys;
}
}

TEST(PathInterpolator, TimeStepsRunThroughTheKeysAndKeysAreThemselves)
{
  Pipeline p(rampKeys({ 0.65, 0.7, 0.75, 0.8 }));
  p.interpolator->SetNumberOfIntermediateFrames(3);
  p.interpolator->UpdateInformation();
  ASSERT_TRUE(p.catcher->Errors.empty()) << p.catcher->AllErrors();
  vtkInformation* info = p.interpolator->GetOutputInformation(0);
  const int n = info->Length(vtkStreamingDemandDrivenPipeline::TIME_STEPS());
  ASSERT_EQ(n, 3 * 4 + 1);
  const double* steps = info->Get(vtkStreamingDemandDrivenPipeline::TIME_STEPS());
  EXPECT_EQ(steps[0], 0.0);
  EXPECT_EQ(steps[4], 1.0);
  EXPECT_EQ(steps[12], 3.0);
  EXPECT_STREQ(p.interpolator->GetPathParameterName(), "mass");
  vtkImageData* key = p.at(2.0);
  ASSERT_TRUE(p.catcher->Errors.empty()) << p.catcher->AllErrors();
  EXPECT_DOUBLE_EQ(fieldValue(key, "Mass"), 0.75);
  EXPECT_EQ(rgbOf(key), rgbOf(rampKey(0.75).image));
}

// Keys 0.11 M apart on the ramp, where the hole grows between them and swallows the parts of the
// cylinders that reach into it: the filter hands the path's spacetime to the interpolation, so
// that what each pixel of its preview ends on is what the frame predicted with the horizon at
// M = 0.615 shows, and not what the frame predicted without it shows.
TEST(PathInterpolator, ThePreviewKnowsTheHorizonAtItsParameter)
{
  const std::vector<double> masses = { 0.45, 0.56, 0.67, 0.78 };
  Pipeline p(rampKeys(masses));
  vtkImageData* preview = p.at(1.5);
  ASSERT_TRUE(p.catcher->Errors.empty()) << p.catcher->AllErrors();
  const double t = fieldValue(preview, "Mass");
  ASSERT_NEAR(t, 0.615, 1e-12);
  std::vector<std::vector<asrt::RayRecord>> records;
  for (double m : masses)
    records.push_back(asrt::polyDataToRecords(rampKey(m).hits));
  std::vector<asrt::PathKey> keys;
  for (std::size_t k = 0; k < masses.size(); ++k)
    keys.push_back({ masses[k], &records[k] });
  const asrt::SceneDescription scene = rampScene(t, kSide);
  asrt::PathOptions without;
  without.pointIndex = asrt::kdTreeIndexFactory();
  without.hedgeNearShadow = true; // the preview's
  without.leaveOneOut = false;
  asrt::PathOptions with = without;
  with.spacetimeAt = [hole = scene.spacetime](double m)
  {
    asrt::SpacetimeParameters at = hole;
    at.mass = m;
    return std::shared_ptr<const asrt::Spacetime>(asrt::makeSpacetime(at));
  };
  const asrt::PathFrame a = asrt::interpolateAlongPath(keys, t, kSide, kSide, *scene.scene, with);
  const asrt::PathFrame b =
    asrt::interpolateAlongPath(keys, t, kSide, kSide, *scene.scene, without);
  auto* ending = vtkIntArray::SafeDownCast(preview->GetPointData()->GetArray("Termination"));
  ASSERT_NE(ending, nullptr);
  ASSERT_EQ(ending->GetNumberOfTuples(), kSide * kSide);
  std::size_t unlikeWith = 0, unlikeWithout = 0;
  for (vtkIdType k = 0; k < ending->GetNumberOfTuples(); ++k)
  {
    unlikeWith += ending->GetValue(k) != static_cast<int>(a.records[k].termination);
    unlikeWithout += ending->GetValue(k) != static_cast<int>(b.records[k].termination);
  }
  std::printf("[ path ] the preview at M = %.3f ends unlike the frame predicted with the horizon "
              "at %zu pixels, unlike the one predicted without it at %zu\n",
              t, unlikeWith, unlikeWithout);
  EXPECT_EQ(unlikeWith, 0u);
  EXPECT_GT(unlikeWithout, 10u);
}

// The frame at M = 0.72, between the keys 0.70 and 0.75, against the frame traced there: with a
// quality target the filter must reach it (within the 1 dB the target allows), re-tracing far
// fewer pixels than the frame has, and its re-traced pixels are the traced frame's (within the
// 8-bit level their predicted neighbours may move a colour by, PathInterpolation.h).
TEST(PathInterpolator, AQualityTargetHoldsAgainstTheTracedFrame)
{
  Pipeline p(rampKeys({ 0.65, 0.7, 0.75, 0.8 }));
  const double time = 1.4; // key 1 (0.70) + 0.4 of the way to key 2 (0.75)
  vtkImageData* preview = p.at(time);
  ASSERT_TRUE(p.catcher->Errors.empty()) << p.catcher->AllErrors();
  const double mass = fieldValue(preview, "Mass");
  EXPECT_NEAR(mass, 0.72, 1e-12);
  EXPECT_NEAR(fieldValue(preview, "PathParameter"), 0.72, 1e-12);
  const TracedFrame truth = traceWith(
    [mass](vtkGeodesicSource* s)
    {
      s->SetSceneFileName(scenePath("fig4-mass-start.json").c_str());
      s->SetResolution(kSide, kSide);
      s->SetMass(mass);
    });
  const std::vector<std::uint8_t> expected = rgbOf(truth.image);
  const double plain = asrt::psnr(view(rgbOf(preview), kSide, kSide), view(expected, kSide, kSide));
  const vtkIdType must = p.interpolator->GetLastMustRetraceCount();
  EXPECT_EQ(p.interpolator->GetLastRetracedCount(), 0);
  p.interpolator->HoldToConvergedOff();
  for (double target : { 30.0, 38.0, 46.0 })
  {
    p.interpolator->SetQualityTarget(target);
    vtkImageData* frame = p.at(time);
    ASSERT_TRUE(p.catcher->Errors.empty()) << p.catcher->AllErrors();
    dump(frame, "path-" + std::to_string(int(target)));
    const std::vector<std::uint8_t> rgb = rgbOf(frame);
    const double q = asrt::psnr(view(rgb, kSide, kSide), view(expected, kSide, kSide));
    const vtkIdType retraced = p.interpolator->GetLastRetracedCount();
    std::printf("[ path ] %dx%d M = %.2f: preview %.1f dB (%lld must re-trace); target %.0f: "
                "%.1f dB (estimated %.1f), %lld re-traced of %d\n",
                kSide, kSide, mass, plain, static_cast<long long>(must), target, q,
                p.interpolator->GetLastEstimatedPsnr(), static_cast<long long>(retraced),
                kSide * kSide);
    EXPECT_GE(q, target - 1.0);
    EXPECT_GE(retraced, must);
    EXPECT_LT(retraced, kSide * kSide / 2);
    auto* method =
      vtkUnsignedCharArray::SafeDownCast(frame->GetPointData()->GetArray("PathMethod"));
    ASSERT_NE(method, nullptr);
    vtkIdType marked = 0;
    for (vtkIdType k = 0; k < method->GetNumberOfTuples(); ++k)
      if (method->GetValue(k) == static_cast<unsigned char>(asrt::PathMethod::Retraced))
      {
        ++marked;
        for (int c = 0; c < 3; ++c)
          ASSERT_LE(std::abs(int(rgb[3 * k + c]) - int(expected[3 * k + c])), 2) << "pixel " << k;
      }
    EXPECT_EQ(marked, retraced);
  }
}

// The same frame against its converged picture (4 × 4 filtered samples a pixel, every centre ray
// traced), which the keys' own settings reach only to within a few dB: held to the converged
// picture (the default), the frame meets the target there, and says what the settings reach.
TEST(PathInterpolator, AQualityTargetHoldsAgainstTheConvergedPicture)
{
  Pipeline p(rampKeys({ 0.65, 0.7, 0.75, 0.8 }));
  const double time = 1.4;
  const std::vector<std::uint8_t> converged = rgbOf(tracedAt072(4).image);
  const double settingsDb =
    asrt::psnr(view(rgbOf(tracedAt072(1).image), kSide, kSide), view(converged, kSide, kSide));
  for (double target : { 30.0, 34.0 })
  {
    p.interpolator->SetQualityTarget(target);
    vtkImageData* frame = p.at(time);
    ASSERT_TRUE(p.catcher->Errors.empty()) << p.catcher->AllErrors();
    const double q = asrt::psnr(view(rgbOf(frame), kSide, kSide), view(converged, kSide, kSide));
    const double settingsBound = fieldValue(frame, "SettingsPsnr");
    std::printf("[ path ] target %.0f against converged: %.1f dB (estimated %.1f); the keys' "
                "settings at M = 0.72 score %.1f dB there, their bound %.1f dB\n",
                target, q, fieldValue(frame, "EstimatedPsnr"), settingsDb, settingsBound);
    EXPECT_GE(q, target - 1.0);
    EXPECT_EQ(settingsBound, p.interpolator->GetLastSettingsPsnr());
    EXPECT_LE(settingsBound, settingsDb + 3.0);
    if (p.interpolator->GetLastConvergedCount() == 0)
    {
      EXPECT_LE(fieldValue(frame, "EstimatedPsnr"), settingsBound);
    }
  }
}

TEST(PathInterpolator, ATargetAboveTheKeysSettingsRaisesTheRenderingWhereTheyErr)
{
  Pipeline p(rampKeys({ 0.65, 0.7, 0.75, 0.8 }));
  const double time = 1.4;
  // The converged picture, the one that judges targets above 36 dB (asrt::convergedSideFor:
  // 8 × 8, which the refinement traces with there), and a denser one (16 × 16) nothing traces
  // with.
  const std::vector<std::uint8_t> converged = rgbOf(tracedAt072(4).image);
  const std::vector<std::uint8_t> judge = rgbOf(tracedAt072(8).image);
  const std::vector<std::uint8_t> dense = rgbOf(tracedAt072(16).image);
  const double settingsDb =
    asrt::psnr(view(rgbOf(tracedAt072(1).image), kSide, kSide), view(converged, kSide, kSide));
  // Off: held to about the keys' own bound, with a warning.
  p.interpolator->RaiseRenderingForTargetOff();
  p.interpolator->SetQualityTarget(30.0);
  const double bound = fieldValue(p.at(time), "SettingsPsnr");
  const double target = std::min(bound + 2.0, 41.0);
  p.interpolator->SetQualityTarget(target);
  p.catcher->Clear();
  vtkImageData* held = p.at(time);
  ASSERT_TRUE(p.catcher->Errors.empty()) << p.catcher->AllErrors();
  EXPECT_FALSE(p.catcher->Warnings.empty());
  EXPECT_EQ(p.interpolator->GetLastConvergedCount(), 0);
  EXPECT_LT(fieldValue(held, "EstimatedPsnr"), target);
  const double heldDense = asrt::psnr(view(rgbOf(held), kSide, kSide), view(dense, kSide, kSide));
  ASSERT_GT(target, 36.0); // judged against 8 × 8
  // On (the default): the frame reaches the target.
  p.interpolator->RaiseRenderingForTargetOn();
  p.catcher->Clear();
  vtkImageData* frame = p.at(time);
  ASSERT_TRUE(p.catcher->Errors.empty()) << p.catcher->AllErrors();
  EXPECT_TRUE(p.catcher->Warnings.empty());
  const double q4 = asrt::psnr(view(rgbOf(frame), kSide, kSide), view(converged, kSide, kSide));
  const double q = asrt::psnr(view(rgbOf(frame), kSide, kSide), view(judge, kSide, kSide));
  const double qDense = asrt::psnr(view(rgbOf(frame), kSide, kSide), view(dense, kSide, kSide));
  const vtkIdType convergedPixels = p.interpolator->GetLastConvergedCount();
  std::printf("[ path ] target %.1f (the keys' settings at M = 0.72: %.1f dB, their bound %.1f): "
              "%.1f dB against 4x4, %.1f against 8x8, %.1f against 16x16 (estimated %.1f; %lld "
              "pixels traced converged, %lld re-traced); held to the keys' settings %.1f against "
              "16x16\n",
              target, settingsDb, bound, q4, q, qDense, fieldValue(frame, "EstimatedPsnr"),
              static_cast<long long>(convergedPixels),
              static_cast<long long>(p.interpolator->GetLastRetracedCount()), heldDense);
  EXPECT_GT(convergedPixels, 0);
  EXPECT_EQ(fieldValue(frame, "ConvergedPixels"), static_cast<double>(convergedPixels));
  EXPECT_GE(fieldValue(frame, "EstimatedPsnr"), target - 1e-9);
  EXPECT_GE(q, target - 1.0);
  EXPECT_GE(qDense, target - 1.0);
  EXPECT_GT(qDense, heldDense);
}

TEST(PathInterpolator, BadKeysAndSettingsAreRefusedByName)
{
  {
    Pipeline p(rampKeys({ 0.7 }));
    p.at(0.0);
    EXPECT_TRUE(p.catcher->Mentions("at least 2 key frames")) << p.catcher->AllErrors();
  }
  {
    Pipeline p(rampKeys({ 0.7, 0.8, 0.75 }));
    p.at(0.5);
    EXPECT_TRUE(p.catcher->Mentions("must change monotonically")) << p.catcher->AllErrors();
  }
  {
    Pipeline p(rampKeys({ 0.7, 0.75 }));
    p.interpolator->SetQualityTarget(150);
    p.at(0.5);
    EXPECT_TRUE(p.catcher->Mentions("QualityTarget must lie in")) << p.catcher->AllErrors();
  }
  {
    Pipeline p(rampKeys({ 0.7, 0.75 }));
    p.interpolator->SetQualityTarget(std::nan(""));
    p.at(0.5);
    EXPECT_TRUE(p.catcher->Mentions("QualityTarget must lie in")) << p.catcher->AllErrors();
  }
  {
    Pipeline p(rampKeys({ 0.7, 0.75 }));
    p.interpolator->SetNumberOfIntermediateFrames(0);
    p.at(0.5);
    EXPECT_TRUE(p.catcher->Mentions("NumberOfIntermediateFrames")) << p.catcher->AllErrors();
  }
  {
    const TracedFrame small = traceWith(
      [](vtkGeodesicSource* s)
      {
        s->SetSceneFileName(scenePath("fig4-mass-start.json").c_str());
        s->SetResolution(kSide / 2, kSide / 2);
        s->SetMass(0.75);
      });
    Pipeline p({ rampKey(0.7).hits, small.hits });
    p.at(0.5);
    EXPECT_TRUE(p.catcher->Mentions("different resolutions")) << p.catcher->AllErrors();
  }
}
