#include "vtkGeodesicFrameInterpolator.h"

#include "AlgorithmAbort.h"

#include "FrameInterpolation.h"
#include "GeodesicFrameMatching.h"
#include "GeodesicRecordArrays.h"
#include "GeodesicSceneLoading.h"
#include "InterpolatorPipeline.h"
#include "KdTreeIndex.h"
#include "RayStore.h"
#include "SceneFile.h"
#include "Spacetime.h"
#include "StoreConnection.h"
#include "vtkGeodesicSource.h"

#include "vtkAlgorithmOutput.h"
#include "vtkCommand.h"
#include "vtkDoubleArray.h"
#include "vtkExecutive.h"
#include "vtkFieldData.h"
#include "vtkImageData.h"
#include "vtkInformation.h"
#include "vtkInformationVector.h"
#include "vtkIntArray.h"
#include "vtkObjectFactory.h"
#include "vtkPNGWriter.h"
#include "vtkPointData.h"
#include "vtkPolyData.h"
#include "vtkStreamingDemandDrivenPipeline.h"
#include "vtkUnsignedCharArray.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

vtkStandardNewMacro(vtkGeodesicFrameInterpolator);

namespace
{
const char* const kFrameName[2] = { "frame A", "frame B" };

/// Keeps the first error of the internal source, which is this filter's error: its message
/// alone, without VTK's "ERROR: In <file>, line <n>" framing and "<Class> (<address>): " prefix,
/// and without the executive's report of the failed request that follows it.
class ErrorCollector : public vtkCommand
{
public:
  static ErrorCollector* New() { return new ErrorCollector; }
  void Execute(vtkObject*, unsigned long, void* data) override
  {
    if (!this->Text.empty())
      return;
    std::string text = data ? static_cast<const char*>(data) : "";
    const std::size_t prefix = text.find("): ");
    if (prefix != std::string::npos)
      text = text.substr(prefix + 3);
    this->Text = text.substr(0, text.find('\n'));
    if (this->Text.empty())
      this->Text = "unknown error";
  }
  std::string Text;
};

}

struct vtkGeodesicFrameInterpolator::Internals
{
  // What RequestInformation validated.
  asrt::SceneDescription Scene[2];
  bool MethodsDiffer = false;

  // The correspondence and splats of the current pair, and what they were built from.
  bool Built = false;
  vtkMTimeType InputTime[2] = { 0, 0 };
  const void* InputData[2] = { nullptr, nullptr };
  double BuiltTolerance = 0, BuiltMagnification = 0, BuiltDepth = 0;
  asrt::SplatSet Splats;
  asrt::InterpolationWorkspace Workspace;
  asrt::InterpolatedFrame Frame;
  std::vector<std::uint8_t> Disagreement;

  asrt::CameraPath Path(int p) const
  {
    return p == LINEAR  ? asrt::CameraPath::Linear
           : p == ORBIT ? asrt::CameraPath::Orbit
                        : asrt::CameraPath::Automatic;
  }

  asrt::FrameParameters At(double t, int path) const
  {
    return asrt::interpolateParameters(asrt::parametersOf(this->Scene[0]),
                                       asrt::parametersOf(this->Scene[1]), t, this->Path(path));
  }

  /// The inputs' scenes, checked against each other, and the camera path checked at every step.
  void Validate(vtkGeodesicFrameInterpolator* self, vtkPolyData* hits[2])
  {
    for (int k = 0; k < 2; ++k)
    {
      if (!hits[k] || hits[k]->GetNumberOfPoints() == 0)
        throw asrt::InvalidParameter(std::string(kFrameName[k]) +
                                     " has no hit points (did its source fail?)");
      try
      {
        this->Scene[k] = asrt::frameFromFieldData(hits[k]->GetFieldData());
      }
      catch (const std::exception& e)
      {
        throw asrt::InvalidParameter(std::string(kFrameName[k]) + ": " + e.what());
      }
      if (this->Scene[k].subset.count > 0)
      {
        std::ostringstream os;
        os << kFrameName[k] << " holds only a subset of its pixels (" << this->Scene[k].subset.count
           << "): only whole frames can be interpolated";
        throw asrt::InvalidParameter(os.str());
      }
    }
    const asrt::CameraParameters &ca = this->Scene[0].camera, &cb = this->Scene[1].camera;
    if (ca.width != cb.width || ca.height != cb.height)
    {
      std::ostringstream os;
      os << "frames of different resolutions: " << ca.width << " x " << ca.height
         << " (frame A) and " << cb.width << " x " << cb.height << " (frame B)";
      throw asrt::InvalidParameter(os.str());
    }
    const std::string difference = asrt::sceneDifference(this->Scene[0], this->Scene[1]);
    if (!difference.empty())
      throw asrt::InvalidParameter("frames A and B are of different scenes (they may differ only "
                                   "in mass, spin, charge, camera position, focal point, view-up "
                                   "and integration method): " +
                                   difference);
    this->MethodsDiffer = this->Scene[0].integrator.method != this->Scene[1].integrator.method;
    const int n = self->NumberOfIntermediateFrames;
    if (n < 1 || n > kMaxIntermediateFrames)
    {
      std::ostringstream os;
      os << "NumberOfIntermediateFrames must lie in [1, " << kMaxIntermediateFrames << "], got "
         << n;
      throw asrt::InvalidParameter(os.str());
    }
    // Exact mode re-traces the scene at every frame: its textures must load before the first.
    if (self->ExactMode)
      try
      {
        asrt::loadScene(asrt::effectiveSceneText(this->Scene[0]).c_str(), nullptr,
                        self->TextureDirectory);
      }
      catch (const std::exception& e)
      {
        throw asrt::InvalidParameter(std::string("exact mode cannot load the frames' scene to "
                                                 "re-trace it: ") +
                                     e.what());
      }
    // Every declared frame must be a valid frame: no eye inside a horizon, |a| ≤ M, ...
    for (int k = 1; k <= n; ++k)
    {
      const double t = static_cast<double>(k) / (n + 1);
      try
      {
        const asrt::FrameParameters p = this->At(t, self->CameraPath);
        const auto st = asrt::makeSpacetime(p.spacetime);
        asrt::CameraParameters c = ca;
        c.position = p.position;
        c.focalPoint = p.focalPoint;
        c.viewUp = p.viewUp;
        asrt::Camera camera(*st, c);
      }
      catch (const std::exception& e)
      {
        std::ostringstream os;
        os << "the frame at t = " << t << " (time step " << k << " of " << n + 1
           << ") is not a valid frame: " << e.what();
        throw asrt::InvalidParameter(os.str());
      }
    }
  }

  /// Builds the correspondence and splats unless they are those of these inputs already.
  void Prepare(vtkGeodesicFrameInterpolator* self, vtkPolyData* hits[2])
  {
    bool current = this->Built && this->BuiltTolerance == self->MatchTolerance &&
                   this->BuiltMagnification == self->MaxMagnification &&
                   this->BuiltDepth == self->DepthTolerance;
    for (int k = 0; k < 2; ++k)
      current =
        current && this->InputData[k] == hits[k] && this->InputTime[k] == hits[k]->GetMTime();
    if (current)
      return;
    this->Built = false;
    if (!(self->MatchTolerance > 0) || !(self->MaxMagnification >= 1) ||
        !(self->DepthTolerance >= 0))
      throw asrt::InvalidParameter("MatchTolerance must be positive, MaxMagnification at least 1 "
                                   "and DepthTolerance non-negative");
    const auto t0 = std::chrono::steady_clock::now();
    const asrt::FrameSamples a = asrt::frameSamplesFromHits(hits[0], this->Scene[0], "frame A");
    const asrt::FrameSamples b = asrt::frameSamplesFromHits(hits[1], this->Scene[1], "frame B");
    self->UpdateProgress(0.1);
    asrt::MatchOptions match;
    match.tolerance = self->MatchTolerance;
    const asrt::Correspondence c =
      asrt::matchFrames(a, b, asrt::kdTreeIndexFactory(), match,
                        [self](double f) { self->UpdateProgress(0.1 + 0.5 * f); });
    asrt::InterpolationOptions opt;
    opt.maxMagnification = static_cast<float>(self->MaxMagnification);
    opt.depthTolerance = static_cast<float>(self->DepthTolerance);
    this->Splats = asrt::buildSplats(a, b, c, opt);
    self->CorrespondenceSeconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    ++self->CorrespondenceBuilds;
    for (int k = 0; k < 2; ++k)
    {
      this->InputData[k] = hits[k];
      this->InputTime[k] = hits[k]->GetMTime();
    }
    this->BuiltTolerance = self->MatchTolerance;
    this->BuiltMagnification = self->MaxMagnification;
    this->BuiltDepth = self->DepthTolerance;
    this->Built = true;
  }

  /// Exact mode: traces (or reads back) the pixels the interpolation cannot vouch for at t and
  /// puts them into the frame. Returns the re-traced records.
  std::vector<asrt::RayRecord> Retrace(vtkGeodesicFrameInterpolator* self, double t)
  {
    const asrt::InterpolatedFrame& f = this->Frame;
    const int W = f.width;
    asrt::renderDisagreement(this->Splats, t, this->Disagreement, this->Workspace);
    std::vector<std::pair<int, int>> pixels;
    for (std::size_t p = 0; p < f.pixelClass.size(); ++p)
      if (f.pixelClass[p] == asrt::PixelClass::HoleFilled ||
          f.pixelClass[p] == asrt::PixelClass::Ambiguous ||
          this->Disagreement[p] > self->RetraceDisagreement)
        pixels.emplace_back(static_cast<int>(p % W), static_cast<int>(p / W));
    if (pixels.empty())
      return {};
    const asrt::FrameParameters p = this->At(t, self->CameraPath);
    vtkNew<vtkGeodesicSource> source;
    vtkNew<ErrorCollector> errors;
    source->AddObserver(vtkCommand::ErrorEvent, errors);
    source->GetExecutive()->AddObserver(vtkCommand::ErrorEvent, errors);
    const std::string text = asrt::effectiveSceneText(this->Scene[0]);
    source->SetSceneText(text.c_str());
    source->SetTextureDirectory(self->TextureDirectory);
    source->SetMass(p.spacetime.mass);
    source->SetSpin(p.spacetime.spin);
    source->SetCharge(p.spacetime.charge);
    source->SetCameraPosition(p.position.data());
    source->SetFocalPoint(p.focalPoint.data());
    source->SetViewUp(p.viewUp.data());
    if (this->MethodsDiffer)
      source->SetIntegrationMethod("auto"); // each end resolved "auto" for its own spacetime
    source->SetGridLattice(asrt::scatteredPixelRendering(this->Scene[0].rendering).gridLattice);
    vtkNew<vtkIntArray> subset;
    subset->SetNumberOfComponents(2);
    subset->SetNumberOfTuples(static_cast<vtkIdType>(pixels.size()));
    for (std::size_t k = 0; k < pixels.size(); ++k)
    {
      subset->SetTypedComponent(static_cast<vtkIdType>(k), 0, pixels[k].first);
      subset->SetTypedComponent(static_cast<vtkIdType>(k), 1, pixels[k].second);
    }
    source->SetPixelSubset(subset);

    std::vector<asrt::RayRecord> records;
    std::unique_ptr<asrt::RayStore> store;
    asrt::SceneDescription identity;
    if (self->StoreRetracedRays)
    {
      const std::string frameText = source->GetFrameSceneText();
      if (frameText.empty())
        throw asrt::InvalidParameter("re-tracing at t = " + std::to_string(t) + ": " +
                                     errors->Text);
      identity = asrt::parseSceneWithoutImages(frameText);
      store = std::make_unique<asrt::RayStore>(asrt::storeConnection(self->ConnectionString));
      store->migrate();
      if (const auto id = store->findFrame(identity))
      {
        records = store->readFrame(*id);
        self->LastReusedCount = static_cast<vtkIdType>(records.size());
        self->LastStoredFrameId = static_cast<vtkIdType>(*id);
      }
    }
    if (records.empty())
    {
      const auto t0 = std::chrono::steady_clock::now();
      source->Update();
      if (!errors->Text.empty())
        throw asrt::InvalidParameter("re-tracing at t = " + std::to_string(t) + ": " +
                                     errors->Text);
      records = asrt::polyDataToRecords(source->GetHitsOutput());
      const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      if (store)
        self->LastStoredFrameId = static_cast<vtkIdType>(store->writeFrame(
          asrt::frameFromFieldData(source->GetHitsOutput()->GetFieldData()),
          self->Label ? self->Label : "", records, asrt::FrameWriteOptions().tracedIn(seconds)));
    }
    if (records.size() != pixels.size())
    {
      std::ostringstream os;
      os << "re-tracing at t = " << t << " gave " << records.size() << " rays for " << pixels.size()
         << " pixels";
      throw asrt::InvalidParameter(os.str());
    }
    return records;
  }
};

vtkGeodesicFrameInterpolator::vtkGeodesicFrameInterpolator()
  : Impl(new Internals)
{
  this->SetNumberOfInputPorts(2);
  this->SetNumberOfOutputPorts(1);
  this->SetLabel("interpolation re-trace");
}

vtkGeodesicFrameInterpolator::~vtkGeodesicFrameInterpolator()
{
  this->SetTextureDirectory(nullptr);
  this->SetConnectionString(nullptr);
  this->SetLabel(nullptr);
}

int vtkGeodesicFrameInterpolator::FillInputPortInformation(int, vtkInformation* info)
{
  info->Set(vtkAlgorithm::INPUT_REQUIRED_DATA_TYPE(), "vtkPolyData");
  return 1;
}

int vtkGeodesicFrameInterpolator::RequestInformation(vtkInformation*,
                                                     vtkInformationVector** inputVector,
                                                     vtkInformationVector* outputVector)
{
  vtkInformation* outInfo = outputVector->GetInformationObject(0);
  try
  {
    // The output's size and time steps follow from the frames themselves, so they are brought
    // up to date here (a no-op when they are).
    vtkPolyData* hits[2];
    for (int k = 0; k < 2; ++k)
    {
      vtkAlgorithmOutput* connection = this->GetInputConnection(k, 0);
      if (!connection || !connection->GetProducer())
        throw asrt::InvalidParameter(std::string(kFrameName[k]) + " is not connected");
      connection->GetProducer()->Update(connection->GetIndex());
      hits[k] = vtkPolyData::GetData(inputVector[k], 0);
    }
    this->Impl->Validate(this, hits);
  }
  catch (const std::exception& e)
  {
    vtkErrorMacro(<< e.what());
    if (vtkDataObject* out = vtkDataObject::GetData(outputVector, 0))
      out->Initialize();
    return 0;
  }
  const asrt::CameraParameters& c = this->Impl->Scene[0].camera;
  asrt::declareFrameImage(outInfo, c.width, c.height);
  const int n = this->NumberOfIntermediateFrames;
  std::vector<double> steps(static_cast<std::size_t>(n) + 2);
  for (int k = 0; k <= n + 1; ++k)
    steps[static_cast<std::size_t>(k)] = static_cast<double>(k) / (n + 1);
  steps.back() = 1.0;
  const double range[2] = { 0.0, 1.0 };
  outInfo->Set(vtkStreamingDemandDrivenPipeline::TIME_STEPS(), steps.data(),
               static_cast<int>(steps.size()));
  outInfo->Set(vtkStreamingDemandDrivenPipeline::TIME_RANGE(), range, 2);
  return 1;
}

int vtkGeodesicFrameInterpolator::RequestUpdateExtent(vtkInformation*,
                                                      vtkInformationVector** inputVector,
                                                      vtkInformationVector*)
{
  for (int k = 0; k < 2; ++k)
    asrt::requestWholeUntimed(inputVector[k]);
  return 1;
}

int vtkGeodesicFrameInterpolator::RequestData(vtkInformation*, vtkInformationVector** inputVector,
                                              vtkInformationVector* outputVector)
{
  vtkInformation* outInfo = outputVector->GetInformationObject(0);
  vtkImageData* image = vtkImageData::GetData(outputVector, 0);
  this->LastRetracedCount = 0;
  this->LastReusedCount = 0;
  this->LastStoredFrameId = -1;
  try
  {
    double t = 0;
    if (outInfo->Has(vtkStreamingDemandDrivenPipeline::UPDATE_TIME_STEP()))
      t = outInfo->Get(vtkStreamingDemandDrivenPipeline::UPDATE_TIME_STEP());
    if (std::isnan(t))
      throw asrt::InvalidParameter("the requested time is NaN");
    t = std::clamp(t, 0.0, 1.0);
    // RequestInformation validated these inputs: it runs again whenever they change.
    vtkPolyData* hits[2] = { vtkPolyData::GetData(inputVector[0], 0),
                             vtkPolyData::GetData(inputVector[1], 0) };
    if (!hits[0] || !hits[1])
      throw asrt::InvalidParameter("the frames are missing");
    this->Impl->Prepare(this, hits);
    if (this->GetAbortExecute())
    {
      asrt::reportAbort(this);
      image->Initialize();
      return 1;
    }
    this->UpdateProgress(0.6);
    asrt::InterpolatedFrame& f = this->Impl->Frame;
    // The hole at t hides the scene points its horizon has grown over since A or B.
    const double horizon =
      asrt::makeSpacetime(this->Impl->At(t, this->CameraPath).spacetime)->outerHorizon();
    asrt::renderFrame(this->Impl->Splats, t, f, this->Impl->Workspace, asrt::SplatSides::Both,
                      horizon);
    this->UpdateProgress(0.7);

    const int W = f.width, H = f.height;
    const vtkIdType n = static_cast<vtkIdType>(W) * H;
    int ext[6] = { 0, W - 1, 0, H - 1, 0, 0 };
    image->Initialize();
    image->SetExtent(ext);
    image->SetSpacing(1, 1, 1);
    image->SetOrigin(0, 0, 0);
    auto colors = asrt::makeArray<vtkUnsignedCharArray>("Colors", 3, n);
    auto cls = asrt::makeArray<vtkUnsignedCharArray>("InterpolationClass", 1, n);
    auto objectId = asrt::makeArray<vtkIntArray>("ObjectId", 1, n);
    auto order = asrt::makeArray<vtkIntArray>("ImageOrder", 1, n);
    auto pathLength = asrt::makeArray<vtkDoubleArray>("PathLength", 1, n);
    auto termination = asrt::makeArray<vtkIntArray>("Termination", 1, n);
    std::copy(f.rgb.begin(), f.rgb.end(), colors->GetPointer(0));
    static_assert(sizeof(asrt::PixelClass) == sizeof(unsigned char), "classes are bytes");
    std::copy(f.pixelClass.begin(), f.pixelClass.end(),
              reinterpret_cast<asrt::PixelClass*>(cls->GetPointer(0)));
    static_assert(sizeof(int) == sizeof(std::int32_t), "vtkIntArray holds 32-bit values");
    asrt::sourceFieldsOf(this->Impl->Splats, f, objectId->GetPointer(0), order->GetPointer(0),
                         termination->GetPointer(0), pathLength->GetPointer(0));

    if (this->ExactMode && t > 0.0 && t < 1.0)
    {
      const std::vector<asrt::RayRecord> records = this->Impl->Retrace(this, t);
      for (const asrt::RayRecord& r : records)
      {
        const vtkIdType p = static_cast<vtkIdType>(r.j) * W + r.i;
        const auto rgb = asrt::imageColor(r.color);
        for (int c = 0; c < 3; ++c)
          colors->SetTypedComponent(p, c, rgb[static_cast<std::size_t>(c)]);
        cls->SetValue(p, static_cast<unsigned char>(asrt::PixelClass::Retraced));
        objectId->SetValue(p, r.objectId);
        order->SetValue(p, r.imageOrder);
        pathLength->SetValue(p, r.affineLength);
        termination->SetValue(p, static_cast<int>(r.termination));
      }
      this->LastRetracedCount = static_cast<vtkIdType>(records.size());
      auto disagreement = asrt::makeArray<vtkUnsignedCharArray>("Disagreement", 1, n);
      std::copy(this->Impl->Disagreement.begin(), this->Impl->Disagreement.end(),
                disagreement->GetPointer(0));
      image->GetPointData()->AddArray(disagreement);
    }
    this->UpdateProgress(0.95);

    vtkPointData* pd = image->GetPointData();
    pd->SetScalars(colors);
    for (vtkDataArray* a :
         std::initializer_list<vtkDataArray*>{ cls, objectId, order, pathLength, termination })
      pd->AddArray(a);

    // Counted on all threads: one counter bumped per pixel is a chain of dependent increments.
    vtkIdType counts[asrt::kPixelClassCount] = { 0, 0, 0, 0, 0 };
    const unsigned char* classes = cls->GetPointer(0);
    constexpr int classCount = asrt::kPixelClassCount;
#pragma omp parallel for schedule(static) reduction(+ : counts[:classCount]) if (n > 65536)
    for (vtkIdType p = 0; p < n; ++p)
      ++counts[classes[p]];
    double fractions[asrt::kPixelClassCount];
    for (int c = 0; c < asrt::kPixelClassCount; ++c)
      fractions[c] = static_cast<double>(counts[c]) / static_cast<double>(n);
    vtkFieldData* fd = image->GetFieldData();
    asrt::addDoubleField(fd, "InterpolationTime", { t });
    asrt::addDoubleField(fd, "InterpolationFractions",
                         { fractions[0], fractions[1], fractions[2], fractions[3], fractions[4] });
    asrt::addCountField(fd, "HolePixels", static_cast<vtkIdType>(f.holes));
    asrt::addCountField(fd, "RetracedPixels", this->LastRetracedCount);
    const asrt::FrameParameters p = this->Impl->At(t, this->CameraPath);
    asrt::setParametersFieldData(p, fd);
    image->GetInformation()->Set(vtkDataObject::DATA_TIME_STEP(), t);
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

int vtkGeodesicFrameInterpolator::WriteSequence(const char* prefix)
{
  if (!prefix || !*prefix)
  {
    vtkErrorMacro(<< "WriteSequence needs a file name prefix");
    return 0;
  }
  this->UpdateInformation();
  vtkInformation* outInfo = this->GetOutputInformation(0);
  if (!outInfo || !outInfo->Has(vtkStreamingDemandDrivenPipeline::TIME_STEPS()))
    return 0; // RequestInformation has reported why
  const int count = outInfo->Length(vtkStreamingDemandDrivenPipeline::TIME_STEPS());
  const std::vector<double> steps(outInfo->Get(vtkStreamingDemandDrivenPipeline::TIME_STEPS()),
                                  outInfo->Get(vtkStreamingDemandDrivenPipeline::TIME_STEPS()) +
                                    count);
  for (int k = 0; k < count; ++k)
  {
    if (!this->UpdateTimeStep(steps[static_cast<std::size_t>(k)]))
      return 0;
    vtkNew<vtkImageData> frame;
    frame->ShallowCopy(this->GetOutput());
    char name[32];
    std::snprintf(name, sizeof name, "_%04d.png", k);
    vtkNew<vtkPNGWriter> writer;
    writer->SetInputData(frame);
    writer->SetFileName((std::string(prefix) + name).c_str());
    writer->Write();
    if (writer->GetErrorCode() != 0)
    {
      vtkErrorMacro(<< "cannot write " << prefix << name);
      return 0;
    }
  }
  return 1;
}

void vtkGeodesicFrameInterpolator::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "NumberOfIntermediateFrames: " << this->NumberOfIntermediateFrames << "\n";
  os << indent << "CameraPath: " << asrt::toString(this->Impl->Path(this->CameraPath)) << "\n";
  os << indent << "MatchTolerance: " << this->MatchTolerance << "\n";
  os << indent << "MaxMagnification: " << this->MaxMagnification << "\n";
  os << indent << "DepthTolerance: " << this->DepthTolerance << "\n";
  os << indent << "ExactMode: " << this->ExactMode << "\n";
  os << indent << "RetraceDisagreement: " << this->RetraceDisagreement << "\n";
  os << indent << "TextureDirectory: "
     << (this->TextureDirectory ? this->TextureDirectory : "(working directory)") << "\n";
  os << indent << "StoreRetracedRays: " << this->StoreRetracedRays << "\n";
  os << indent << "ConnectionString: "
     << (this->ConnectionString && *this->ConnectionString ? "(set)" : "(default)") << "\n";
  os << indent << "Label: " << (this->Label ? this->Label : "") << "\n";
  os << indent << "CorrespondenceBuilds: " << this->CorrespondenceBuilds << "\n";
  os << indent << "CorrespondenceSeconds: " << this->CorrespondenceSeconds << "\n";
  os << indent << "LastRetracedCount: " << this->LastRetracedCount << "\n";
  os << indent << "LastReusedCount: " << this->LastReusedCount << "\n";
  os << indent << "LastStoredFrameId: " << this->LastStoredFrameId << "\n";
}
