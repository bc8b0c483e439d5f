#include "vtkGeodesicMovieSource.h"

#include "AlgorithmAbort.h"
#include "ErrorEstimate.h"
#include "GeodesicCameraPath.h"
#include "GeodesicMovie.h"
#include "GeodesicRecordArrays.h"
#include "InterpolatorPipeline.h"
#include "RayStore.h"
#include "SceneFile.h"
#include "StoreConnection.h"
#include "vtkGeodesicSource.h"

#include "vtkFieldData.h"
#include "vtkImageData.h"
#include "vtkInformation.h"
#include "vtkInformationVector.h"
#include "vtkNew.h"
#include "vtkObjectFactory.h"
#include "vtkSmartPointer.h"
#include "vtkStreamingDemandDrivenPipeline.h"
#include "vtkStringArray.h"

#include <vtksys/SystemTools.hxx>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <string>

vtkStandardNewMacro(vtkGeodesicMovieSource);

struct vtkGeodesicMovieSource::Internals
{
  std::unique_ptr<asrt::RayStore> Store;
  std::unique_ptr<asrt::MovieMaker> Maker;
  vtkMTimeType MadeAt = 0; ///< the source's MTime the maker was made for
  /// What the maker was made of, to make it again with the raised rendering.
  vtkSmartPointer<vtkGeodesicSource> Source;
  asrt::MoviePath Path;
  bool RenderingChecked = false; ///< whether the rendering was judged against the target
  bool RenderingRaised = false, RenderingLowered = false;
  /// Traced by the maker of the default rendering before it was raised or lowered.
  double ChoosingRays = 0;
};

vtkGeodesicMovieSource::vtkGeodesicMovieSource()
  : Impl(new Internals)
{
  this->SetNumberOfInputPorts(0);
  this->SetPathParameter("mass");
  this->SetStoreLabel("movie");
}

vtkGeodesicMovieSource::~vtkGeodesicMovieSource()
{
  this->SetSceneFileName(nullptr);
  this->SetPathParameter(nullptr);
  this->SetStoreConnection(nullptr);
  this->SetStoreLabel(nullptr);
  this->SetCameraKeysFileName(nullptr);
}

namespace
{
std::string text(const char* s)
{
  return s ? std::string(s) : std::string();
}

std::string number(double v)
{
  std::ostringstream os;
  os << v;
  return os.str();
}

/// The settings' refusals, each naming the setting.
void checkSettings(const char* scene, const std::string& parameter, int frames, double quality,
                   double from, double to, double degrees)
{
  if (text(scene).empty())
    throw asrt::InvalidParameter("SceneFileName: no scene file given");
  if (!vtksys::SystemTools::FileExists(scene, true))
    throw asrt::InvalidParameter("SceneFileName: no such file '" + text(scene) + "'");
  if (frames < 2 || frames > asrt::kMaxMovieFrames)
    throw asrt::InvalidParameter("NumberOfFrames: a movie has 2 to " +
                                 std::to_string(asrt::kMaxMovieFrames) + " frames, got " +
                                 std::to_string(frames));
  if (!(quality > 0.0 && quality <= asrt::kMaxQualityTargetDb))
    throw asrt::InvalidParameter("QualityTarget: the target must lie in (0, 100] dB, got " +
                                 number(quality));
  if (parameter == "cameras")
    return;
  if (parameter == "orbit")
  {
    if (!std::isfinite(degrees) || degrees == 0 || std::abs(degrees) > 360)
      throw asrt::InvalidParameter(
        "OrbitDegrees: must be nonzero and at most 360 in magnitude, got " + number(degrees));
    return;
  }
  if (parameter != "mass" && parameter != "spin" && parameter != "charge")
    throw asrt::InvalidParameter("PathParameter: unknown ramp parameter '" +
                                 parameter.substr(0, 40) +
                                 "' (mass, spin, charge, orbit or cameras)");
  if (!std::isfinite(from) || !std::isfinite(to))
    throw asrt::InvalidParameter("RampFrom, RampTo: must be finite, got " + number(from) + " and " +
                                 number(to));
  if (from == to)
    throw asrt::InvalidParameter("RampFrom, RampTo: equal (" + number(from) + "): no path");
}

/// The key cameras of the file, read whole (at most a scene file's size).
std::vector<asrt::CameraPose> cameraKeys(const char* file)
{
  const std::string name = text(file);
  if (name.empty())
    throw asrt::InvalidParameter("CameraKeysFileName: no key-camera file given");
  std::ifstream in(name, std::ios::binary);
  if (!in || !vtksys::SystemTools::FileExists(name, true))
    throw asrt::InvalidParameter("CameraKeysFileName: cannot read '" + name + "'");
  std::string content;
  char chunk[65536];
  while (in.read(chunk, sizeof chunk) || in.gcount() > 0)
  {
    content.append(chunk, static_cast<std::size_t>(in.gcount()));
    if (content.size() > asrt::kMaxSceneBytes)
      throw asrt::InvalidParameter("CameraKeysFileName: '" + name + "' is larger than " +
                                   std::to_string(asrt::kMaxSceneBytes >> 20) + " MiB");
  }
  try
  {
    return asrt::parseCameraKeys(content, name);
  }
  catch (const asrt::InvalidParameter& e)
  {
    throw asrt::InvalidParameter(std::string("CameraKeysFileName: ") + e.what());
  }
}
}

int vtkGeodesicMovieSource::RequestInformation(vtkInformation*, vtkInformationVector**,
                                               vtkInformationVector* outputVector)
{
  vtkInformation* outInfo = outputVector->GetInformationObject(0);
  Internals& in = *this->Impl;
  try
  {
    if (!in.Maker || in.MadeAt != this->GetMTime())
    {
      in.Maker.reset();
      in.Store.reset();
      in.RenderingChecked = in.RenderingRaised = in.RenderingLowered = false;
      in.ChoosingRays = 0;
      this->RaysTraced = 0;
      const std::string parameter = text(this->PathParameter);
      checkSettings(this->SceneFileName, parameter, this->NumberOfFrames, this->QualityTarget,
                    this->RampFrom, this->RampTo, this->OrbitDegrees);
      vtkNew<vtkGeodesicSource> source;
      source->SetSceneFileName(this->SceneFileName);
      source->SetResolution(this->Resolution);
      asrt::MoviePath path;
      if (parameter == "orbit")
      {
        const std::string sceneText = source->GetFrameSceneText();
        if (sceneText.empty())
          throw asrt::InvalidParameter("SceneFileName: the scene is invalid");
        path = asrt::orbitMoviePath(asrt::sceneCameraOfText(sceneText), this->OrbitDegrees,
                                    this->NumberOfFrames);
      }
      else if (parameter == "cameras")
        path = asrt::cameraKeyMoviePath(cameraKeys(this->CameraKeysFileName), this->NumberOfFrames);
      else
        path = asrt::rampMoviePath(parameter, this->RampFrom, this->RampTo, this->NumberOfFrames);
      std::vector<asrt::MovieFrame> frames = asrt::movieFrames(source, path);
      if (!text(this->StoreConnection).empty())
      {
        const std::string given = text(this->StoreConnection);
        in.Store = std::make_unique<asrt::RayStore>(
          asrt::storeConnection(given == "default" ? "" : given.c_str()));
        in.Store->migrate();
      }
      asrt::MovieSettings settings;
      settings.quality = this->QualityTarget;
      settings.holdToConverged = this->HoldToConverged != 0;
      settings.textureDirectory = vtksys::SystemTools::GetFilenamePath(this->SceneFileName);
      settings.label = text(this->StoreLabel);
      settings.cacheRetraced = true;
      settings.cancelled = [this] { return this->GetAbortExecute() != 0; };
      settings.traceProgress = [this](double f) { this->UpdateProgress(0.05 + 0.9 * f); };
      const double failedShare = this->MaxFailedShare;
      settings.checkTraced = [this, failedShare](const std::vector<asrt::RayRecord>& records, int k)
      {
        double failed = 0, traced = 0;
        for (const asrt::RayRecord& r : records)
        {
          if (r.termination == asrt::Termination::Running)
            continue;
          ++traced;
          if (r.termination == asrt::Termination::NumericalFailure ||
              r.termination == asrt::Termination::StepBudget)
            ++failed;
        }
        if (traced > 0 && failed / traced > failedShare)
          throw asrt::InvalidParameter(
            "frame " + std::to_string(k) + " (" +
            this->Impl->Maker->frames()[static_cast<std::size_t>(k)].describe +
            "): " + number(100 * failed / traced) +
            " % of its rays failed numerically or ran out of "
            "steps, above MaxFailedShare (" +
            number(100 * failedShare) + " %)");
      };
      in.Source = source.Get();
      in.Path = path;
      in.Maker = std::make_unique<asrt::MovieMaker>(std::move(frames), path.parameter,
                                                    in.Store.get(), std::move(settings));
      in.Maker->plan();
      in.MadeAt = this->GetMTime();
    }
  }
  catch (const std::exception& e)
  {
    in.Maker.reset();
    in.Store.reset();
    vtkErrorMacro(<< e.what());
    if (vtkDataObject* out = vtkDataObject::GetData(outputVector, 0))
      out->Initialize();
    return 0;
  }
  asrt::declareFrameImage(outInfo, in.Maker->width(), in.Maker->height());
  std::vector<double> steps;
  for (std::size_t k = 0; k < in.Maker->frames().size(); ++k)
    steps.push_back(static_cast<double>(k));
  const double range[2] = { 0.0, steps.back() };
  outInfo->Set(vtkStreamingDemandDrivenPipeline::TIME_STEPS(), steps.data(),
               static_cast<int>(steps.size()));
  outInfo->Set(vtkStreamingDemandDrivenPipeline::TIME_RANGE(), range, 2);
  return 1;
}

int vtkGeodesicMovieSource::RequestData(vtkInformation*, vtkInformationVector**,
                                        vtkInformationVector* outputVector)
{
  vtkInformation* outInfo = outputVector->GetInformationObject(0);
  vtkImageData* image = vtkImageData::GetData(outputVector, 0);
  Internals& in = *this->Impl;
  try
  {
    if (!in.Maker)
      throw asrt::InvalidParameter("the movie's settings were refused in the information pass");
    const int n = static_cast<int>(in.Maker->frames().size());
    double time = 0;
    if (outInfo->Has(vtkStreamingDemandDrivenPipeline::UPDATE_TIME_STEP()))
      time = outInfo->Get(vtkStreamingDemandDrivenPipeline::UPDATE_TIME_STEP());
    if (std::isnan(time))
      throw asrt::InvalidParameter("the requested time is NaN");
    const int k = static_cast<int>(std::lround(std::clamp(time, 0.0, n - 1.0)));
    this->UpdateProgress(0.05);
    asrt::MovieFrameReport report;
    try
    {
      this->JudgeRendering();
      image->Initialize();
      // A whole frame's records are handed over, not copied (half a gigabyte at 1920×1080).
      const int width = in.Maker->width(), height = in.Maker->height();
      in.Maker->useFrame(k, report,
                         [width, height, image](const std::vector<asrt::RayRecord>& records)
                         { asrt::recordsToImage(records, width, 0, height, image); });
    }
    catch (const asrt::MovieCancelled&)
    {
      this->RaysTraced = in.ChoosingRays + in.Maker->raysTraced();
      asrt::reportAbort(this);
      image->Initialize();
      return 1;
    }
    this->RaysTraced = in.ChoosingRays + in.Maker->raysTraced();
    vtkFieldData* fd = image->GetFieldData();
    vtkNew<vtkStringArray> method;
    method->SetName("FrameMethod");
    method->InsertNextValue(asrt::toString(report.method));
    fd->AddArray(method);
    asrt::addDoubleField(fd, "EstimatedPsnr", { report.estimatedPsnr });
    asrt::addDoubleField(fd, "SettingsPsnr", { report.settingsPsnr });
    asrt::addDoubleField(fd, "ShareRetraced", { report.shareRetraced });
    asrt::addDoubleField(fd, "PathParameter", { in.Maker->frames()[k].s });
    asrt::addCountField(fd, "FrameIndex", k);
    asrt::addCountField(fd, "RenderingRaised", in.RenderingRaised ? 1 : 0);
    asrt::addCountField(fd, "RenderingLowered", in.RenderingLowered ? 1 : 0);
    image->GetInformation()->Set(vtkDataObject::DATA_TIME_STEP(), static_cast<double>(k));
    this->UpdateProgress(1.0);
  }
  catch (const std::exception& e)
  {
    vtkErrorMacro(<< e.what());
    image->Initialize();
    return 0;
  }
  return 1;
}

void vtkGeodesicMovieSource::JudgeRendering()
{
  Internals& in = *this->Impl;
  if (in.RenderingChecked)
    return;
  asrt::RenderingChoice choice;
  if (auto other = in.Maker->withRenderingForTarget(in.Source, in.Path, choice,
                                                    this->RaiseRenderingForTarget != 0,
                                                    this->LowerRenderingForTarget != 0))
  {
    in.ChoosingRays = in.Maker->raysTraced();
    in.Maker = std::move(other);
    in.RenderingRaised = choice.change == asrt::RenderingChoice::Change::Raised ||
                         choice.change == asrt::RenderingChoice::Change::Accurate;
    in.RenderingLowered = choice.change == asrt::RenderingChoice::Change::Lowered;
  }
  in.RenderingChecked = true;
}

int vtkGeodesicMovieSource::GetNumberOfPlannedKeys()
{
  return this->Impl->Maker ? static_cast<int>(this->Impl->Maker->plan().keys().size()) : 0;
}

int vtkGeodesicMovieSource::GetPlannedMethod(int frame)
{
  if (!this->Impl->Maker || frame < 0 ||
      frame >= static_cast<int>(this->Impl->Maker->frames().size()))
    return -1;
  return static_cast<int>(this->Impl->Maker->plan().frames[static_cast<std::size_t>(frame)].method);
}

void vtkGeodesicMovieSource::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "SceneFileName: " << text(this->SceneFileName) << "\n";
  os << indent << "PathParameter: " << text(this->PathParameter) << "\n";
  os << indent << "RampFrom: " << this->RampFrom << "\n";
  os << indent << "RampTo: " << this->RampTo << "\n";
  os << indent << "OrbitDegrees: " << this->OrbitDegrees << "\n";
  os << indent << "CameraKeysFileName: " << text(this->CameraKeysFileName) << "\n";
  os << indent << "NumberOfFrames: " << this->NumberOfFrames << "\n";
  os << indent << "QualityTarget: " << this->QualityTarget << "\n";
  os << indent << "HoldToConverged: " << this->HoldToConverged << "\n";
  os << indent << "RaiseRenderingForTarget: " << this->RaiseRenderingForTarget << "\n";
  os << indent << "LowerRenderingForTarget: " << this->LowerRenderingForTarget << "\n";
  os << indent << "Resolution: " << this->Resolution[0] << " " << this->Resolution[1] << "\n";
  os << indent << "StoreConnection: " << (text(this->StoreConnection).empty() ? "(none)" : "(set)")
     << "\n";
  os << indent << "StoreLabel: " << text(this->StoreLabel) << "\n";
  os << indent << "MaxFailedShare: " << this->MaxFailedShare << "\n";
  os << indent << "RaysTraced: " << this->RaysTraced << "\n";
}
