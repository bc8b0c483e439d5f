// vtkGeodesicMovieSource against frames this test traces itself with vtkGeodesicSource at each
// frame's parameters: its time steps are the movie's frames, its key frames are the traced frames
// bit for bit, its interpolated frames meet the quality target less 1 dB, asking for a frame again
// traces no ray, and bad settings are errors naming the setting.
#include "FiltersTestUtilities.h"
#include "vtkGeodesicMovieSource.h"

#include "GeodesicMovie.h"
#include "MoviePlan.h"

#include "vtkCallbackCommand.h"
#include "vtkFieldData.h"
#include "vtkInformation.h"
#include "vtkStreamingDemandDrivenPipeline.h"
#include "vtkStringArray.h"
#include "vtkUnsignedCharArray.h"

#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <string>
#include <vector>

using namespace asrt::testing;

namespace
{
constexpr int kSide = 48;
constexpr int kFrames = 7;
constexpr double kFrom = 0.65, kTo = 0.8;

/// The movie of CLI.Movie: Figs. 4-5's scene, the mass from 0.65 to 0.8 in 7 frames at 48×48.
void configure(vtkGeodesicMovieSource* movie)
{
  movie->SetSceneFileName(scenePath("fig4-mass-start.json").c_str());
  movie->SetPathParameter("mass");
  movie->SetRampFrom(kFrom);
  movie->SetRampTo(kTo);
  movie->SetNumberOfFrames(kFrames);
  movie->SetQualityTarget(35);
  // Held to the frames traced at their parameters, the truth these tests trace: at this size the
  // default rendering itself scores near 30 dB against the converged pictures.
  movie->HoldToConvergedOff();
  movie->SetResolution(kSide, kSide);
}

double massOf(int k)
{
  return kFrom + (kTo - kFrom) * k / (kFrames - 1);
}

/// The frame traced whole at mass M by the source itself: the truth.
vtkSmartPointer<vtkImageData> traced(double mass)
{
  vtkNew<vtkGeodesicSource> source;
  source->SetSceneFileName(scenePath("fig4-mass-start.json").c_str());
  source->SetResolution(kSide, kSide);
  source->SetMass(mass);
  source->Update();
  auto image = vtkSmartPointer<vtkImageData>::New();
  image->DeepCopy(source->GetOutput());
  return image;
}

vtkSmartPointer<vtkImageData> frameAt(vtkGeodesicMovieSource* movie, double time)
{
  movie->UpdateTimeStep(time);
  auto image = vtkSmartPointer<vtkImageData>::New();
  image->DeepCopy(movie->GetOutput());
  return image;
}

std::vector<unsigned char> colours(vtkImageData* image)
{
  std::vector<unsigned char> rgb;
  vtkDataArray* c = image->GetPointData()->GetArray("Colors");
  if (!c)
    return rgb;
  for (vtkIdType p = 0; p < c->GetNumberOfTuples(); ++p)
    for (int k = 0; k < 3; ++k)
      rgb.push_back(static_cast<unsigned char>(c->GetComponent(p, k)));
  return rgb;
}

/// 10 log10(255² / MSE) over the three channels.
double psnrOf(const std::vector<unsigned char>& a, const std::vector<unsigned char>& b)
{
  double sum = 0;
  for (std::size_t k = 0; k < a.size(); ++k)
    sum += (double(a[k]) - double(b[k])) * (double(a[k]) - double(b[k]));
  if (sum == 0)
    return std::numeric_limits<double>::infinity();
  return 10 * std::log10(255.0 * 255.0 / (sum / static_cast<double>(a.size())));
}

std::string methodOf(vtkImageData* image)
{
  auto* a = vtkStringArray::SafeDownCast(image->GetFieldData()->GetAbstractArray("FrameMethod"));
  return a && a->GetNumberOfValues() == 1 ? a->GetValue(0) : std::string();
}

/// The colours of Figs. 4-5's scene at `mass` traced by a vtkGeodesicSource at 24x24, with the
/// preset, cap and supersample given where they are not empty or 0.
std::vector<unsigned char> coloursAt24(double mass, const std::string& preset, int maxRays,
                                       int supersample)
{
  vtkNew<vtkGeodesicSource> source;
  source->SetSceneFileName(scenePath("fig4-mass-start.json").c_str());
  source->SetResolution(24, 24);
  source->SetMass(mass);
  if (!preset.empty())
    source->SetIntegrationPreset(preset.c_str());
  if (maxRays)
    source->SetMaxRaysPerPixel(maxRays);
  if (supersample)
    source->SetSupersample(supersample);
  source->Update();
  return colours(source->GetOutput());
}

double fieldOf(vtkImageData* image, const char* name)
{
  vtkDataArray* a = image->GetFieldData()->GetArray(name);
  return a ? a->GetComponent(0, 0) : std::numeric_limits<double>::quiet_NaN();
}
}

TEST(MovieSource, TimeStepsAreTheFramesKeysAreTracedFramesAndTheRestMeetTheTarget)
{
  vtkNew<vtkGeodesicMovieSource> movie;
  vtkNew<MessageCatcher> catcher;
  watch(movie, catcher);
  configure(movie);
  movie->UpdateInformation();
  ASSERT_TRUE(catcher->Errors.empty()) << catcher->AllErrors();
  vtkInformation* info = movie->GetOutputInformation(0);
  ASSERT_TRUE(info->Has(vtkStreamingDemandDrivenPipeline::TIME_STEPS()));
  ASSERT_EQ(info->Length(vtkStreamingDemandDrivenPipeline::TIME_STEPS()), kFrames);
  const double* steps = info->Get(vtkStreamingDemandDrivenPipeline::TIME_STEPS());
  for (int k = 0; k < kFrames; ++k)
    EXPECT_EQ(steps[k], k);
  // The plan is asrt movie's for these settings (CLI.Movie checks the same), final once the keys
  // are made (at the first frame asked for): each frame is checked by the method it was made by.
  int keys = 0, interpolated = 0;
  for (int k = 0; k < kFrames; ++k)
  {
    const auto method = static_cast<asrt::FrameMethod>(movie->GetPlannedMethod(k));
    const vtkSmartPointer<vtkImageData> frame = frameAt(movie, k);
    ASSERT_TRUE(catcher->Errors.empty()) << catcher->AllErrors();
    EXPECT_EQ(fieldOf(frame, "FrameIndex"), k);
    EXPECT_DOUBLE_EQ(fieldOf(frame, "PathParameter"), massOf(k));
    const vtkSmartPointer<vtkImageData> truth = traced(massOf(k));
    if (method == asrt::FrameMethod::Key || method == asrt::FrameMethod::Traced)
    {
      ++keys;
      EXPECT_EQ(methodOf(frame), asrt::toString(method));
      EXPECT_EQ(fieldOf(frame, "ShareRetraced"), 1.0);
      EXPECT_TRUE(std::isinf(fieldOf(frame, "EstimatedPsnr")));
      for (const char* name :
           { "Colors", "ObjectId", "ImageOrder", "PathLength", "Termination", "RaysPerPixel" })
      {
        vtkDataArray* a = frame->GetPointData()->GetArray(name);
        vtkDataArray* b = truth->GetPointData()->GetArray(name);
        ASSERT_TRUE(a && b) << name;
        ASSERT_EQ(a->GetNumberOfValues(), b->GetNumberOfValues()) << name;
        vtkIdType differ = 0;
        for (vtkIdType v = 0; v < a->GetNumberOfValues(); ++v)
        {
          const double x = a->GetVariantValue(v).ToDouble(), y = b->GetVariantValue(v).ToDouble();
          if (std::memcmp(&x, &y, sizeof x) != 0)
            ++differ;
        }
        EXPECT_EQ(differ, 0) << name << " of key frame " << k;
      }
    }
    else
    {
      ASSERT_EQ(method, asrt::FrameMethod::Interpolated) << "frame " << k;
      ++interpolated;
      EXPECT_EQ(methodOf(frame), "interpolated");
      const double share = fieldOf(frame, "ShareRetraced");
      EXPECT_GT(share, 0.0);
      EXPECT_LT(share, 1.0);
      EXPECT_GE(fieldOf(frame, "EstimatedPsnr"), 35.0);
      EXPECT_GE(psnrOf(colours(frame), colours(truth)), 34.0) << "frame " << k;
    }
  }
  EXPECT_EQ(keys, movie->GetNumberOfPlannedKeys());
  EXPECT_EQ(keys + interpolated, kFrames);
  EXPECT_GT(interpolated, 0) << "the movie no longer interpolates: this test checks nothing of it";
}

TEST(MovieSource, AFrameAskedForAgainTracesNothing)
{
  vtkNew<vtkGeodesicMovieSource> movie;
  vtkNew<MessageCatcher> catcher;
  watch(movie, catcher);
  configure(movie);
  // The first frame asked for makes the keys; the plan is final then.
  frameAt(movie, 0);
  ASSERT_TRUE(catcher->Errors.empty()) << catcher->AllErrors();
  const double afterKeys = movie->GetRaysTraced();
  EXPECT_GT(afterKeys, 2.0 * kSide * kSide);
  std::vector<int> interpolated;
  for (int k = 0; k < kFrames; ++k)
    if (static_cast<asrt::FrameMethod>(movie->GetPlannedMethod(k)) ==
        asrt::FrameMethod::Interpolated)
      interpolated.push_back(k);
  ASSERT_GE(interpolated.size(), 2u) << "this test needs two interpolated frames";
  const int one = interpolated.front(), other = interpolated.back();
  const vtkSmartPointer<vtkImageData> first = frameAt(movie, one);
  ASSERT_TRUE(catcher->Errors.empty()) << catcher->AllErrors();
  const double afterFirst = movie->GetRaysTraced();
  EXPECT_GT(afterFirst, afterKeys); // its re-traced pixels
  frameAt(movie, other);
  const double afterOther = movie->GetRaysTraced();
  EXPECT_GT(afterOther, afterFirst); // the other frame's own re-traced pixels
  const vtkSmartPointer<vtkImageData> again = frameAt(movie, one);
  EXPECT_EQ(movie->GetRaysTraced(), afterOther);
  EXPECT_EQ(colours(again), colours(first));
  frameAt(movie, 3);
  const double afterThree = movie->GetRaysTraced();
  frameAt(movie, 3.2); // the nearest frame, 3, made already
  EXPECT_EQ(movie->GetRaysTraced(), afterThree);
  ASSERT_TRUE(catcher->Errors.empty()) << catcher->AllErrors();

  // A changed setting is another movie: planned and made again.
  movie->SetQualityTarget(30);
  frameAt(movie, one);
  EXPECT_GT(movie->GetRaysTraced(), 0.0);
  EXPECT_LT(movie->GetRaysTraced(), afterOther);
}

TEST(MovieSource, BadSettingsAreErrorsNamingTheSetting)
{
  struct Case
  {
    const char* field;
    std::function<void(vtkGeodesicMovieSource*)> set;
  };
  const std::vector<Case> cases = {
    { "NumberOfFrames", [](vtkGeodesicMovieSource* m) { m->SetNumberOfFrames(1); } },
    { "QualityTarget", [](vtkGeodesicMovieSource* m) { m->SetQualityTarget(0); } },
    { "QualityTarget", [](vtkGeodesicMovieSource* m) { m->SetQualityTarget(-3); } },
    { "QualityTarget", [](vtkGeodesicMovieSource* m) { m->SetQualityTarget(101); } },
    { "QualityTarget", [](vtkGeodesicMovieSource* m)
      { m->SetQualityTarget(std::numeric_limits<double>::quiet_NaN()); } },
    { "PathParameter", [](vtkGeodesicMovieSource* m) { m->SetPathParameter("temperature"); } },
    { "RampFrom", [](vtkGeodesicMovieSource* m) { m->SetRampTo(kFrom); } },
    { "OrbitDegrees",
      [](vtkGeodesicMovieSource* m)
      {
        m->SetPathParameter("orbit");
        m->SetOrbitDegrees(400);
      } },
    { "SceneFileName", [](vtkGeodesicMovieSource* m) { m->SetSceneFileName(nullptr); } },
    { "SceneFileName",
      [](vtkGeodesicMovieSource* m) { m->SetSceneFileName("/nonexistent/scene.json"); } },
    // A ramp that sends the spin past the mass: the frame and the scene's complaint.
    { "frame 4 (spin = 1.1)",
      [](vtkGeodesicMovieSource* m)
      {
        m->SetSceneFileName(scenePath("kerr-disk.json").c_str());
        m->SetPathParameter("spin");
        m->SetRampFrom(0.3);
        m->SetRampTo(1.5);
      } },
  };
  for (const Case& c : cases)
  {
    vtkNew<vtkGeodesicMovieSource> movie;
    vtkNew<MessageCatcher> catcher;
    watch(movie, catcher);
    configure(movie);
    c.set(movie);
    movie->UpdateTimeStep(1);
    EXPECT_TRUE(catcher->Mentions(c.field)) << c.field << ": " << catcher->AllErrors();
    EXPECT_EQ(movie->GetOutput()->GetNumberOfPoints(), 0) << c.field;
    EXPECT_EQ(movie->GetRaysTraced(), 0.0) << c.field;
  }
}

TEST(MovieSource, AnOrbitHasItsAnglesAsParameters)
{
  vtkNew<vtkGeodesicMovieSource> movie;
  vtkNew<MessageCatcher> catcher;
  watch(movie, catcher);
  movie->SetSceneFileName(scenePath("fig1-cylinders.json").c_str());
  movie->SetPathParameter("orbit");
  movie->SetOrbitDegrees(20);
  movie->SetNumberOfFrames(3);
  movie->SetResolution(24, 24);
  // At 24x24 the scene's rendering does not reach the default target against the converged
  // picture: kept as it is, the frames are the ones vtkGeodesicSource traces by default.
  movie->RaiseRenderingForTargetOff();
  const vtkSmartPointer<vtkImageData> last = frameAt(movie, 2);
  ASSERT_TRUE(catcher->Errors.empty()) << catcher->AllErrors();
  EXPECT_DOUBLE_EQ(fieldOf(last, "PathParameter"), 20.0);
  EXPECT_EQ(last->GetNumberOfPoints(), 24 * 24);
  std::ostringstream printed;
  movie->Print(printed);
  EXPECT_NE(printed.str().find("OrbitDegrees: 20"), std::string::npos);
}

TEST(MovieSource, ACameraPathThroughKeyCamerasEndsAtTheLastKey)
{
  const std::string file = ::testing::TempDir() + "movie-source-cams.json";
  {
    std::ofstream out(file);
    out << R"({"keys": [
      {"position": [0, -30, 8], "focalPoint": [0, 0, 0], "viewUp": [0, 0, 1]},
      {"position": [6, -29, 9], "focalPoint": [0, 0, 0], "viewUp": [0, 0, 1]},
      {"position": [12, -27, 10], "focalPoint": [0, 0, 0], "viewUp": [0, 0, 1]}]})";
  }
  vtkNew<vtkGeodesicMovieSource> movie;
  vtkNew<MessageCatcher> catcher;
  watch(movie, catcher);
  movie->SetSceneFileName(scenePath("fig1-cylinders.json").c_str());
  movie->SetPathParameter("cameras");
  movie->SetCameraKeysFileName(file.c_str());
  movie->SetNumberOfFrames(3);
  movie->SetResolution(24, 24);
  // At 24x24 the scene's rendering does not reach the default target against the converged
  // picture: kept as it is, the frames are the ones vtkGeodesicSource traces by default.
  movie->RaiseRenderingForTargetOff();
  const vtkSmartPointer<vtkImageData> last = frameAt(movie, 2);
  ASSERT_TRUE(catcher->Errors.empty()) << catcher->AllErrors();
  EXPECT_DOUBLE_EQ(fieldOf(last, "PathParameter"), 2.0); // the third key
  vtkNew<vtkGeodesicSource> traced;
  traced->SetSceneFileName(scenePath("fig1-cylinders.json").c_str());
  traced->SetResolution(24, 24);
  traced->SetCameraPosition(12, -27, 10);
  traced->SetFocalPoint(0, 0, 0);
  traced->SetViewUp(0, 0, 1);
  traced->Update();
  EXPECT_EQ(colours(last), colours(traced->GetOutput()));

  // A file of one key: an error naming the setting and the file's field.
  {
    std::ofstream out(file);
    out << R"({"keys": [{"position": [0, -30, 8], "focalPoint": [0, 0, 0], "viewUp": [0, 0, 1]}]})";
  }
  movie->Modified();
  movie->UpdateTimeStep(0);
  EXPECT_TRUE(catcher->Mentions("CameraKeysFileName")) << catcher->AllErrors();
  EXPECT_TRUE(catcher->Mentions("at least 2 key cameras")) << catcher->AllErrors();
  std::remove(file.c_str());
}

TEST(MovieSource, ATargetTheScenesRenderingDoesNotReachRaisesItToTheAccuratePreset)
{
  vtkNew<vtkGeodesicMovieSource> movie;
  vtkNew<MessageCatcher> catcher;
  watch(movie, catcher);
  configure(movie);
  movie->HoldToConvergedOn();
  movie->SetNumberOfFrames(3);
  movie->SetResolution(24, 24);
  movie->SetQualityTarget(40); // the default rendering reaches about 31 dB at this size
  auto tracedAt = [](double mass, const char* preset)
  { return coloursAt24(mass, preset ? preset : "", 0, 0); };
  // The last frame is a key of every plan: the frame traced with the rendering chosen.
  const vtkSmartPointer<vtkImageData> raised = frameAt(movie, 2);
  ASSERT_TRUE(catcher->Errors.empty()) << catcher->AllErrors();
  EXPECT_EQ(fieldOf(raised, "RenderingRaised"), 1.0);
  EXPECT_EQ(colours(raised), tracedAt(kTo, "accurate"));
  EXPECT_NE(colours(raised), tracedAt(kTo, nullptr));
  // Its rays count the default rendering's two end frames traced to judge it.
  const double withJudging = movie->GetRaysTraced();

  movie->RaiseRenderingForTargetOff();
  const vtkSmartPointer<vtkImageData> kept = frameAt(movie, 2);
  ASSERT_TRUE(catcher->Errors.empty()) << catcher->AllErrors();
  EXPECT_EQ(fieldOf(kept, "RenderingRaised"), 0.0);
  EXPECT_EQ(colours(kept), tracedAt(kTo, nullptr));
  EXPECT_GT(withJudging, movie->GetRaysTraced());

  // A target the scene's rendering reaches keeps it.
  movie->RaiseRenderingForTargetOn();
  movie->SetQualityTarget(20);
  const vtkSmartPointer<vtkImageData> low = frameAt(movie, 2);
  ASSERT_TRUE(catcher->Errors.empty()) << catcher->AllErrors();
  EXPECT_EQ(fieldOf(low, "RenderingRaised"), 0.0);
  EXPECT_EQ(colours(low), tracedAt(kTo, nullptr));
}

TEST(MovieSource, ATargetACheaperCapReachesLowersTheRenderingBetweenTheEnds)
{
  vtkNew<vtkGeodesicMovieSource> movie;
  vtkNew<MessageCatcher> catcher;
  watch(movie, catcher);
  configure(movie);
  movie->HoldToConvergedOn();
  movie->SetNumberOfFrames(5);
  movie->SetResolution(24, 24);
  movie->SetQualityTarget(20); // the default rendering reaches about 31 dB at this size
  auto tracedAt = [](double mass, int maxRays, bool converged)
  { return converged ? coloursAt24(mass, "accurate", 0, 4) : coloursAt24(mass, "", maxRays, 0); };
  const double step = (kTo - kFrom) / 4;
  std::vector<vtkSmartPointer<vtkImageData>> frames;
  for (int k = 0; k < 5; ++k)
    frames.push_back(frameAt(movie, k));
  ASSERT_TRUE(catcher->Errors.empty()) << catcher->AllErrors();
  for (int k = 0; k < 5; ++k)
  {
    EXPECT_EQ(fieldOf(frames[k], "RenderingLowered"), 1.0) << "frame " << k;
    EXPECT_EQ(fieldOf(frames[k], "RenderingRaised"), 0.0) << "frame " << k;
    // Every frame meets the target against the converged picture the test traces.
    EXPECT_GE(psnrOf(colours(frames[k]), tracedAt(kFrom + k * step, 0, true)), 19.0)
      << "frame " << k;
  }
  // The ends, traced to judge the rendering, stay as the default rendering traced them; the
  // frames between that the plan traces whole are the cheaper cap's.
  EXPECT_EQ(colours(frames[0]), tracedAt(kFrom, 0, false));
  EXPECT_EQ(colours(frames[4]), tracedAt(kTo, 0, false));
  int whole = 0;
  for (int k = 1; k < 4; ++k)
  {
    const int method = movie->GetPlannedMethod(k);
    if (method == static_cast<int>(asrt::FrameMethod::Key) ||
        method == static_cast<int>(asrt::FrameMethod::Traced))
    {
      ++whole;
      EXPECT_EQ(colours(frames[k]), tracedAt(kFrom + k * step, asrt::kLoweredRaysPerPixel, false))
        << "frame " << k;
      EXPECT_NE(colours(frames[k]), tracedAt(kFrom + k * step, 0, false)) << "frame " << k;
    }
  }
  EXPECT_GT(whole, 0);

  // Off, or at a target the cheaper cap does not reach with room to spare, the default stays.
  movie->LowerRenderingForTargetOff();
  const vtkSmartPointer<vtkImageData> kept = frameAt(movie, 2);
  EXPECT_EQ(fieldOf(kept, "RenderingLowered"), 0.0);
  movie->LowerRenderingForTargetOn();
  movie->RaiseRenderingForTargetOff();
  movie->SetQualityTarget(30);
  const vtkSmartPointer<vtkImageData> near = frameAt(movie, 2);
  ASSERT_TRUE(catcher->Errors.empty()) << catcher->AllErrors();
  EXPECT_EQ(fieldOf(near, "RenderingLowered"), 0.0);
}

TEST(MovieSource, AnAbortStopsTheFrameAndTheNextRequestMakesIt)
{
  vtkNew<vtkGeodesicMovieSource> movie;
  vtkNew<MessageCatcher> catcher;
  watch(movie, catcher);
  configure(movie);
  // Abort at the first progress report of the first key frame's trace.
  vtkNew<vtkCallbackCommand> abort;
  abort->SetCallback(
    [](vtkObject* caller, unsigned long, void*, void* callData)
    {
      const double progress = *static_cast<double*>(callData);
      if (progress > 0.05 && progress < 1.0)
        static_cast<vtkAlgorithm*>(caller)->SetAbortExecute(1);
    });
  const unsigned long tag = movie->AddObserver(vtkCommand::ProgressEvent, abort);
  movie->UpdateTimeStep(1);
  EXPECT_TRUE(catcher->Errors.empty()) << catcher->AllErrors();
  EXPECT_EQ(movie->GetOutput()->GetNumberOfPoints(), 0);
  EXPECT_LT(movie->GetRaysTraced(), 1.0 * kSide * kSide); // stopped inside the first key frame
  movie->RemoveObserver(tag);
  movie->SetAbortExecute(0);
  const vtkSmartPointer<vtkImageData> frame = frameAt(movie, 1);
  EXPECT_TRUE(catcher->Errors.empty()) << catcher->AllErrors();
  EXPECT_EQ(frame->GetNumberOfPoints(), kSide * kSide);
  EXPECT_EQ(methodOf(frame),
            asrt::toString(static_cast<asrt::FrameMethod>(movie->GetPlannedMethod(1))));
}
