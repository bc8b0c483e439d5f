#include "vtkGeodesicPathInterpolator.h"

#include "AlgorithmAbort.h"

#include "ErrorEstimate.h"
#include "FrameMatching.h"
#include "FrameTracer.h"
#include "GeodesicRecordArrays.h"
#include "GeodesicSceneLoading.h"
#include "InterpolatorPipeline.h"
#include "KdTreeIndex.h"
#include "LeaveOneOut.h"
#include "PathInterpolation.h"
#include "SceneFile.h"
#include "SettingsError.h"
#include "Spacetime.h"

#include "vtkAlgorithmOutput.h"
#include "vtkDoubleArray.h"
#include "vtkFieldData.h"
#include "vtkFloatArray.h"
#include "vtkImageData.h"
#include "vtkInformation.h"
#include "vtkInformationVector.h"
#include "vtkObjectFactory.h"
#include "vtkPointData.h"
#include "vtkPolyData.h"
#include "vtkStreamingDemandDrivenPipeline.h"
#include "vtkUnsignedCharArray.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

vtkStandardNewMacro(vtkGeodesicPathInterpolator);

namespace
{
std::string keyName(std::size_t k)
{
  return "key frame " + std::to_string(k);
}

/// The spacetime along the keys' path at ±s (the interpolation's parameter, `direction` · s):
/// between the two keys around s, their parameters interpolated as the frame's are.
std::function<std::shared_ptr<const asrt::Spacetime>(double)> spacetimeAlongKeys(
  const std::vector<asrt::SceneDescription>& scenes, const std::vector<double>& S, double direction)
{
  return [&scenes, &S, direction](double signedS) -> std::shared_ptr<const asrt::Spacetime>
  {
    const double s = direction * signedS;
    std::size_t b = 0;
    while (b + 2 < S.size() && direction * S[b + 1] <= signedS)
      ++b;
    const double span = S[b + 1] - S[b];
    const double fraction = span != 0.0 ? std::clamp((s - S[b]) / span, 0.0, 1.0) : 0.0;
    const asrt::FrameParameters p =
      asrt::interpolateParameters(asrt::parametersOf(scenes[b]), asrt::parametersOf(scenes[b + 1]),
                                  fraction, asrt::CameraPath::Automatic);
    return asrt::makeSpacetime(p.spacetime);
  };
}

/// The angle between the eye's directions from the hole in two frames, in degrees.
double eyeAngle(const asrt::SceneDescription& a, const asrt::SceneDescription& b)
{
  const asrt::Vec3 u = a.camera.position.normalized(), v = b.camera.position.normalized();
  return std::atan2(u.cross(v).norm(), u.dot(v)) * 180.0 / M_PI;
}
}

struct vtkGeodesicPathInterpolator::Internals
{
  std::vector<asrt::SceneDescription> Scenes; ///< the keys', without image textures
  std::vector<double> S;                      ///< the path parameter per key
  std::string ParameterName;
  /// +1 if s increases along the keys, −1 if it decreases (the interpolation runs in ±s).
  double Direction = 1.0;

  // The keys' records and what they were read from.
  std::vector<std::vector<asrt::RayRecord>> Records;
  std::vector<const void*> InputData;
  std::vector<vtkMTimeType> InputTime;
  // The scene with its textures, for shading and tracing, and the text it was loaded from.
  asrt::SceneDescription Shading;
  std::string ShadingText, ShadingDirectory;
  /// Each key's own error against its converged picture, once measured (reset when it is read
  /// again).
  std::vector<std::optional<asrt::SettingsError>> KeyError;
  /// The moved edges' correspondences between keys, kept across time steps: every frame between
  /// two keys matches the same pairs (kept by the records' content, so keys read again are safe).
  std::shared_ptr<asrt::PathMatchCache> Matches = std::make_shared<asrt::PathMatchCache>();
  std::shared_ptr<asrt::LeaveOneOutCache> LeftOut = std::make_shared<asrt::LeaveOneOutCache>();

  /// The keys' scenes, checked against each other, and the path parameter.
  void Validate(vtkGeodesicPathInterpolator* self, const std::vector<vtkPolyData*>& hits)
  {
    if (hits.size() < 2)
      throw asrt::InvalidParameter("at least 2 key frames are needed, got " +
                                   std::to_string(hits.size()));
    this->Scenes.assign(hits.size(), {});
    for (std::size_t k = 0; k < hits.size(); ++k)
    {
      if (!hits[k] || hits[k]->GetNumberOfPoints() == 0)
        throw asrt::InvalidParameter(keyName(k) + " has no hit points (did its source fail?)");
      try
      {
        this->Scenes[k] = asrt::frameFromFieldData(hits[k]->GetFieldData());
      }
      catch (const std::exception& e)
      {
        throw asrt::InvalidParameter(keyName(k) + ": " + e.what());
      }
      if (this->Scenes[k].subset.count > 0)
        throw asrt::InvalidParameter(keyName(k) +
                                     " holds only a subset of its pixels: only whole frames can "
                                     "be key frames");
      const asrt::CameraParameters &c0 = this->Scenes[0].camera, &ck = this->Scenes[k].camera;
      if (c0.width != ck.width || c0.height != ck.height)
      {
        std::ostringstream os;
        os << "key frames of different resolutions: " << c0.width << " x " << c0.height
           << " (key frame 0) and " << ck.width << " x " << ck.height << " (" << keyName(k) << ")";
        throw asrt::InvalidParameter(os.str());
      }
      const std::string difference = asrt::sceneDifference(this->Scenes[0], this->Scenes[k]);
      if (!difference.empty())
        throw asrt::InvalidParameter("key frames 0 and " + std::to_string(k) +
                                     " are of different scenes: " + difference);
    }
    const int n = self->NumberOfIntermediateFrames;
    if (n < 1 || n > kMaxIntermediateFrames)
      throw asrt::InvalidParameter("NumberOfIntermediateFrames must lie in [1, " +
                                   std::to_string(kMaxIntermediateFrames) + "], got " +
                                   std::to_string(n));
    if (!(self->QualityTarget >= 0.0 && self->QualityTarget <= asrt::kMaxQualityTargetDb))
    {
      std::ostringstream os;
      os << "QualityTarget must lie in [0, " << asrt::kMaxQualityTargetDb
         << "] dB (0: no re-tracing), got " << self->QualityTarget;
      throw asrt::InvalidParameter(os.str());
    }
    if (!(self->ProbeFraction > 0.0 && self->ProbeFraction <= 1.0))
    {
      std::ostringstream os;
      os << "ProbeFraction must lie in (0, 1], got " << self->ProbeFraction;
      throw asrt::InvalidParameter(os.str());
    }
    this->ChooseParameter();
  }

  /// The first of mass, spin, charge that differs between the keys, else the eye's accumulated
  /// angle about the hole; it must change strictly monotonically.
  void ChooseParameter()
  {
    const std::size_t K = this->Scenes.size();
    using Get = double (*)(const asrt::SceneDescription&);
    const std::pair<const char*, Get> quantities[] = {
      { "mass", [](const asrt::SceneDescription& d) { return d.spacetime.mass; } },
      { "spin", [](const asrt::SceneDescription& d) { return d.spacetime.spin; } },
      { "charge", [](const asrt::SceneDescription& d) { return d.spacetime.charge; } },
    };
    this->S.assign(K, 0.0);
    this->ParameterName.clear();
    for (const auto& [name, get] : quantities)
    {
      bool differs = false;
      for (std::size_t k = 1; k < K; ++k)
        differs = differs || get(this->Scenes[k]) != get(this->Scenes[0]);
      if (!differs)
        continue;
      this->ParameterName = name;
      for (std::size_t k = 0; k < K; ++k)
        this->S[k] = get(this->Scenes[k]);
      break;
    }
    if (this->ParameterName.empty())
    {
      this->ParameterName = "orbit angle";
      for (std::size_t k = 1; k < K; ++k)
        this->S[k] = this->S[k - 1] + eyeAngle(this->Scenes[k - 1], this->Scenes[k]);
    }
    this->Direction = this->S[1] > this->S[0] ? 1.0 : -1.0;
    for (std::size_t k = 1; k < K; ++k)
      if (!(this->Direction * (this->S[k] - this->S[k - 1]) > 0.0))
      {
        std::ostringstream os;
        os.precision(17);
        os << "the path parameter (" << this->ParameterName
           << ") must change monotonically along the key frames: " << keyName(k - 1) << " has "
           << this->S[k - 1] << ", " << keyName(k) << " " << this->S[k];
        throw asrt::InvalidParameter(os.str());
      }
  }

  /// The keys' records in pixel order, read again only when an input changed.
  void Read(const std::vector<vtkPolyData*>& hits)
  {
    const std::size_t K = hits.size();
    this->Records.resize(K);
    this->KeyError.resize(K);
    this->InputData.resize(K, nullptr);
    this->InputTime.resize(K, 0);
    const asrt::CameraParameters& c = this->Scenes[0].camera;
    for (std::size_t k = 0; k < K; ++k)
    {
      if (this->InputData[k] == hits[k] && this->InputTime[k] == hits[k]->GetMTime())
        continue;
      std::vector<asrt::RayRecord> r = asrt::polyDataToRecords(hits[k]);
      std::sort(r.begin(), r.end(),
                [](const asrt::RayRecord& a, const asrt::RayRecord& b)
                { return a.j != b.j ? a.j < b.j : a.i < b.i; });
      if (r.size() != static_cast<std::size_t>(c.width) * c.height)
        throw asrt::InvalidParameter(keyName(k) + " has " + std::to_string(r.size()) +
                                     " rays, its frame " + std::to_string(c.width * c.height) +
                                     " pixels");
      this->Records[k] = std::move(r);
      this->KeyError[k].reset();
      this->InputData[k] = hits[k];
      this->InputTime[k] = hits[k]->GetMTime();
    }
  }

  /// The scene of key k with its textures: the shading scene at the key's parameters.
  asrt::SceneDescription KeyScene(std::size_t k) const
  {
    asrt::SceneDescription d = this->Shading;
    asrt::applyParameters(asrt::parametersOf(this->Scenes[k]), d);
    d.integrator = this->Scenes[k].integrator;
    d.rendering = this->Scenes[k].rendering;
    return d;
  }

  /// Key k's own error against its converged picture: probes traced converged, once a key.
  const asrt::SettingsError& KeySettingsError(std::size_t k)
  {
    if (!this->KeyError[k])
    {
      asrt::SceneDescription d = this->KeyScene(k);
      if (asrt::isConvergedRendering(d.rendering))
        this->KeyError[k] = asrt::SettingsError{};
      else
      {
        d.rendering = asrt::convergedRendering(asrt::settingsReferenceSide(d.rendering));
        const asrt::FrameTracer converged(d);
        const asrt::CameraParameters& c = d.camera;
        this->KeyError[k] = asrt::measureSettingsError(this->Records[k], c.width, c.height,
                                                       asrt::pixelTracerOf(converged));
      }
    }
    return *this->KeyError[k];
  }

  /// The scene with its image textures, loaded again only when its text or folder changed.
  void LoadShading(const char* directory)
  {
    const std::string text = asrt::effectiveSceneText(this->Scenes[0]);
    const std::string dir = directory ? directory : "";
    if (this->Shading.scene && text == this->ShadingText && dir == this->ShadingDirectory)
      return;
    try
    {
      this->Shading = asrt::loadScene(text.c_str(), nullptr, directory);
    }
    catch (const std::exception& e)
    {
      throw asrt::InvalidParameter(std::string("cannot load the key frames' scene to shade "
                                               "interpolated pixels: ") +
                                   e.what());
    }
    this->ShadingText = text;
    this->ShadingDirectory = dir;
  }
};

vtkGeodesicPathInterpolator::vtkGeodesicPathInterpolator()
  : Impl(new Internals)
{
  this->SetNumberOfInputPorts(1);
  this->SetNumberOfOutputPorts(1);
}

vtkGeodesicPathInterpolator::~vtkGeodesicPathInterpolator()
{
  this->SetTextureDirectory(nullptr);
}

const char* vtkGeodesicPathInterpolator::GetPathParameterName() const
{
  return this->Impl->ParameterName.c_str();
}

int vtkGeodesicPathInterpolator::FillInputPortInformation(int, vtkInformation* info)
{
  info->Set(vtkAlgorithm::INPUT_REQUIRED_DATA_TYPE(), "vtkPolyData");
  info->Set(vtkAlgorithm::INPUT_IS_REPEATABLE(), 1);
  return 1;
}

namespace
{
std::vector<vtkPolyData*> keyFrames(vtkAlgorithm* self, vtkInformationVector* in)
{
  std::vector<vtkPolyData*> hits;
  for (int k = 0; k < self->GetNumberOfInputConnections(0); ++k)
    hits.push_back(vtkPolyData::GetData(in, k));
  return hits;
}
}

int vtkGeodesicPathInterpolator::RequestInformation(vtkInformation*,
                                                    vtkInformationVector** inputVector,
                                                    vtkInformationVector* outputVector)
{
  vtkInformation* outInfo = outputVector->GetInformationObject(0);
  try
  {
    // The output's size and time steps follow from the keys themselves.
    for (int k = 0; k < this->GetNumberOfInputConnections(0); ++k)
    {
      vtkAlgorithmOutput* connection = this->GetInputConnection(0, k);
      if (connection && connection->GetProducer())
        connection->GetProducer()->Update(connection->GetIndex());
    }
    this->Impl->Validate(this, keyFrames(this, inputVector[0]));
  }
  catch (const std::exception& e)
  {
    vtkErrorMacro(<< e.what());
    if (vtkDataObject* out = vtkDataObject::GetData(outputVector, 0))
      out->Initialize();
    return 0;
  }
  const asrt::CameraParameters& c = this->Impl->Scenes[0].camera;
  asrt::declareFrameImage(outInfo, c.width, c.height);
  const int n = this->NumberOfIntermediateFrames;
  const int keys = static_cast<int>(this->Impl->Scenes.size());
  std::vector<double> steps;
  for (int k = 0; k + 1 < keys; ++k)
    for (int j = 0; j <= n; ++j)
      steps.push_back(k + static_cast<double>(j) / (n + 1));
  steps.push_back(keys - 1);
  const double range[2] = { 0.0, static_cast<double>(keys - 1) };
  outInfo->Set(vtkStreamingDemandDrivenPipeline::TIME_STEPS(), steps.data(),
               static_cast<int>(steps.size()));
  outInfo->Set(vtkStreamingDemandDrivenPipeline::TIME_RANGE(), range, 2);
  return 1;
}

int vtkGeodesicPathInterpolator::RequestUpdateExtent(vtkInformation*,
                                                     vtkInformationVector** inputVector,
                                                     vtkInformationVector*)
{
  asrt::requestWholeUntimed(inputVector[0]);
  return 1;
}

namespace
{
/// The output's point arrays beyond the source's, and its field data.
void addPathArrays(const asrt::PathFrame& f, vtkImageData* image)
{
  const vtkIdType n = static_cast<vtkIdType>(f.records.size());
  auto method = asrt::makeArray<vtkUnsignedCharArray>("PathMethod", 1, n);
  std::copy(f.method.begin(), f.method.end(), method->GetPointer(0));
  auto estimate = asrt::makeArray<vtkFloatArray>("ErrorEstimate", 1, n);
  std::copy(f.estimate.begin(), f.estimate.end(), estimate->GetPointer(0));
  image->GetPointData()->AddArray(method);
  image->GetPointData()->AddArray(estimate);
  const std::vector<std::size_t> counts = f.counts();
  std::vector<double> shares;
  for (std::size_t c : counts)
    shares.push_back(static_cast<double>(c) / static_cast<double>(std::max<vtkIdType>(n, 1)));
  auto fractions = vtkSmartPointer<vtkDoubleArray>::New();
  fractions->SetName("PathMethodFractions");
  fractions->SetNumberOfComponents(static_cast<int>(shares.size()));
  fractions->InsertNextTuple(shares.data());
  image->GetFieldData()->AddArray(fractions);
}
}

int vtkGeodesicPathInterpolator::RequestData(vtkInformation*, vtkInformationVector** inputVector,
                                             vtkInformationVector* outputVector)
{
  vtkInformation* outInfo = outputVector->GetInformationObject(0);
  vtkImageData* image = vtkImageData::GetData(outputVector, 0);
  this->LastRetracedCount = 0;
  this->LastConvergedCount = 0;
  this->LastMustRetraceCount = 0;
  this->LastEstimatedPsnr = 0.0;
  this->LastSettingsPsnr = 0.0;
  Internals& in = *this->Impl;
  try
  {
    const std::vector<vtkPolyData*> hits = keyFrames(this, inputVector[0]);
    if (hits.size() != in.Scenes.size())
      throw asrt::InvalidParameter("the key frames changed since the pipeline's information pass");
    const int K = static_cast<int>(hits.size());
    double time = 0;
    if (outInfo->Has(vtkStreamingDemandDrivenPipeline::UPDATE_TIME_STEP()))
      time = outInfo->Get(vtkStreamingDemandDrivenPipeline::UPDATE_TIME_STEP());
    if (std::isnan(time))
      throw asrt::InvalidParameter("the requested time is NaN");
    time = std::clamp(time, 0.0, static_cast<double>(K - 1));
    in.Read(hits);
    in.LoadShading(this->TextureDirectory);
    this->UpdateProgress(0.1);

    // The inner pair (a, a + 1) and the fraction of the way from a to a + 1.
    const int a = std::min(static_cast<int>(std::floor(time)), K - 2);
    const double fraction = time - a;
    const double s = fraction >= 1.0 ? in.S[a + 1] : in.S[a] + fraction * (in.S[a + 1] - in.S[a]);
    std::vector<asrt::PathKey> keys;
    for (int k = 0; k < K; ++k)
      keys.push_back({ in.Direction * in.S[k], &in.Records[static_cast<std::size_t>(k)] });
    const asrt::CameraParameters& cam = in.Scenes[0].camera;
    asrt::PathOptions options;
    options.pointIndex = asrt::kdTreeIndexFactory();
    options.matchCache = in.Matches;
    options.hedgeNearShadow = !(this->QualityTarget > 0.0); // the plain preview
    // The keys' leave-one-out errors only order the pixels to re-trace.
    options.leaveOneOut = this->QualityTarget > 0.0;
    options.leaveOneOutCache = in.LeftOut;
    options.spacetimeAt = spacetimeAlongKeys(in.Scenes, in.S, in.Direction);
    asrt::PathFrame f = asrt::interpolateAlongPath(keys, in.Direction * s, cam.width, cam.height,
                                                   *in.Shading.scene, options);
    this->UpdateProgress(0.3);
    const asrt::FrameParameters p = asrt::interpolateParameters(
      asrt::parametersOf(in.Scenes[a]), asrt::parametersOf(in.Scenes[a + 1]), fraction,
      asrt::CameraPath::Automatic);
    this->LastMustRetraceCount =
      static_cast<vtkIdType>(f.counts()[static_cast<std::size_t>(asrt::PathMethod::Retrace)]);
    const double none = std::numeric_limits<double>::infinity();
    if (this->QualityTarget > 0.0 && !(fraction > 0.0 && fraction < 1.0))
    {
      // A key itself: its own error is the frame's.
      const std::size_t key = static_cast<std::size_t>(fraction >= 1.0 ? a + 1 : a);
      this->LastSettingsPsnr = this->HoldToConverged ? in.KeySettingsError(key).psnr() : none;
      this->LastEstimatedPsnr = this->LastSettingsPsnr;
    }
    else if (this->QualityTarget > 0.0)
    {
      const asrt::SettingsError settings =
        this->HoldToConverged ? asrt::pooled(in.KeySettingsError(static_cast<std::size_t>(a)),
                                             in.KeySettingsError(static_cast<std::size_t>(a + 1)))
                              : asrt::SettingsError{};
      this->LastSettingsPsnr = settings.psnr();
      const bool raise = this->HoldToConverged && this->RaiseRenderingForTarget;
      if (this->LastSettingsPsnr < this->QualityTarget && !raise)
        vtkWarningMacro(<< "QualityTarget " << this->QualityTarget
                        << " dB is above what the key frames' settings reach against the "
                           "converged picture around t (their bound: "
                        << this->LastSettingsPsnr
                        << " dB): re-tracing with them holds the frame to within about 1 dB of "
                           "that; RaiseRenderingForTarget, or key frames traced with a better "
                           "rendering (the accurate preset, a supersample), raise it");
      asrt::SceneDescription atT = in.Shading;
      asrt::applyParameters(p, atT);
      if (in.Scenes[a].integrator.method != in.Scenes[a + 1].integrator.method)
        atT.integrator.method = "auto"; // each key resolved "auto" for its own spacetime
      atT.rendering = asrt::scatteredPixelRendering(atT.rendering);
      const asrt::FrameTracer tracer(atT);
      asrt::PathCompletion done;
      if (raise && asrt::settingsFallShort(settings, this->QualityTarget))
      {
        // The rendering that judges the target (convergedSideFor): the refined pixels carry none
        // of the error it measures.
        asrt::SceneDescription convergedAtT = atT;
        convergedAtT.rendering =
          asrt::convergedRendering(asrt::convergedSideFor(this->QualityTarget));
        const asrt::FrameTracer converged(convergedAtT);
        done =
          asrt::completePathFrame(f, asrt::pixelTracerOf(tracer), this->QualityTarget,
                                  this->ProbeFraction, asrt::refinementFor(settings, converged));
      }
      else
        done = asrt::completePathFrame(f, tracer, this->QualityTarget, this->ProbeFraction,
                                       settings.mseBound());
      this->LastRetracedCount = static_cast<vtkIdType>(done.retraced);
      this->LastConvergedCount = static_cast<vtkIdType>(done.refined);
      this->LastEstimatedPsnr = done.estimatedPsnr;
    }
    if (this->GetAbortExecute())
    {
      asrt::reportAbort(this);
      image->Initialize();
      return 1;
    }
    image->Initialize();
    asrt::recordsToImage(f.records, cam.width, 0, cam.height, image);
    addPathArrays(f, image);
    vtkFieldData* fd = image->GetFieldData();
    asrt::addDoubleField(fd, "PathParameter", { s });
    asrt::addCountField(fd, "RetracedPixels", this->LastRetracedCount);
    asrt::addCountField(fd, "ConvergedPixels", this->LastConvergedCount);
    if (this->QualityTarget > 0.0)
    {
      asrt::addDoubleField(fd, "EstimatedPsnr", { this->LastEstimatedPsnr });
      asrt::addDoubleField(fd, "SettingsPsnr", { this->LastSettingsPsnr });
    }
    asrt::setParametersFieldData(p, fd);
    image->GetInformation()->Set(vtkDataObject::DATA_TIME_STEP(), time);
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

void vtkGeodesicPathInterpolator::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "NumberOfIntermediateFrames: " << this->NumberOfIntermediateFrames << "\n";
  os << indent << "QualityTarget: " << this->QualityTarget << "\n";
  os << indent << "HoldToConverged: " << this->HoldToConverged << "\n";
  os << indent << "RaiseRenderingForTarget: " << this->RaiseRenderingForTarget << "\n";
  os << indent << "ProbeFraction: " << this->ProbeFraction << "\n";
  os << indent << "TextureDirectory: " << (this->TextureDirectory ? this->TextureDirectory : "")
     << "\n";
  os << indent << "PathParameterName: " << this->Impl->ParameterName << "\n";
  os << indent << "LastRetracedCount: " << this->LastRetracedCount << "\n";
  os << indent << "LastConvergedCount: " << this->LastConvergedCount << "\n";
  os << indent << "LastMustRetraceCount: " << this->LastMustRetraceCount << "\n";
  os << indent << "LastEstimatedPsnr: " << this->LastEstimatedPsnr << "\n";
  os << indent << "LastSettingsPsnr: " << this->LastSettingsPsnr << "\n";
}
