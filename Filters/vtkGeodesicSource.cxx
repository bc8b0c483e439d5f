#include "vtkGeodesicSource.h"

#include "AlgorithmAbort.h"

#include "FrameTracer.h"
#include "GeodesicRecordArrays.h"
#include "GeodesicSceneLoading.h"
#include "RowBands.h"
#include "TextureFiles.h"

#include "vtkCommand.h"
#include "vtkExecutive.h"
#include "vtkFieldData.h"
#include "vtkImageData.h"
#include "vtkImageReader2.h"
#include "vtkImageReader2Factory.h"
#include "vtkInformation.h"
#include "vtkInformationVector.h"
#include "vtkIntArray.h"
#include "vtkNew.h"
#include "vtkObjectFactory.h"
#include "vtkPointData.h"
#include "vtkPolyData.h"
#include "vtkStreamingDemandDrivenPipeline.h"
#include "vtkStringArray.h"

#include <vtksys/SystemTools.hxx>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <tuple>
#include <utility>

vtkStandardNewMacro(vtkGeodesicSource);

namespace
{
const double kNaN = std::numeric_limits<double>::quiet_NaN();

bool isSet(double v)
{
  return !std::isnan(v);
}

/// Bytes a pixel of the outputs needs: the image's arrays (23) and its hit point's (the point,
/// the record's fields and the vertex: 276), rounded up.
constexpr double kOutputBytesPerPixel = 24.0 + 280.0;

/// Rays a frame may draw as polylines: each keeps a point a step, hundreds of times a pixel's
/// record, so their count is bounded apart from the frame's memory.
constexpr long long kMaxPolylines = 100000;

double physicalMemory()
{
  const long pages = sysconf(_SC_PHYS_PAGES), size = sysconf(_SC_PAGE_SIZE);
  return pages > 0 && size > 0 ? static_cast<double>(pages) * size : 8e9;
}
}

vtkCxxSetSmartPointerMacro(vtkGeodesicSource, PixelSubset, vtkIntArray);
vtkCxxSetSmartPointerMacro(vtkGeodesicSource, PolylinePixels, vtkIntArray);

vtkIntArray* vtkGeodesicSource::GetPixelSubset()
{
  return this->PixelSubset;
}

vtkIntArray* vtkGeodesicSource::GetPolylinePixels()
{
  return this->PolylinePixels;
}

void vtkGeodesicSource::ClearPolylinePixels()
{
  this->SetPolylinePixels(nullptr);
}

void vtkGeodesicSource::AddPolylinePixel(int i, int j)
{
  vtkNew<vtkIntArray> pixels;
  pixels->SetNumberOfComponents(2);
  if (this->PolylinePixels)
    pixels->DeepCopy(this->PolylinePixels);
  const int ij[2] = { i, j };
  pixels->InsertNextTypedTuple(ij);
  this->SetPolylinePixels(pixels);
}

vtkGeodesicSource::vtkGeodesicSource()
  : Mass(kNaN)
  , Spin(kNaN)
  , Charge(kNaN)
  , CameraPosition{ kNaN, kNaN, kNaN }
  , FocalPoint{ kNaN, kNaN, kNaN }
  , ViewUp{ kNaN, kNaN, kNaN }
  , ViewAngle(kNaN)
  , IntegrationStep(kNaN)
{
  this->SetNumberOfInputPorts(0);
  this->SetNumberOfOutputPorts(3);
}

vtkGeodesicSource::~vtkGeodesicSource()
{
  this->SetSceneFileName(nullptr);
  this->SetSceneText(nullptr);
  this->SetTextureDirectory(nullptr);
  this->SetIntegrationMethod(nullptr);
  this->SetIntegrationPreset(nullptr);
  this->SetAntialias(nullptr);
}

vtkImageData* vtkGeodesicSource::GetImageOutput()
{
  return vtkImageData::SafeDownCast(this->GetOutputDataObject(0));
}

vtkPolyData* vtkGeodesicSource::GetHitsOutput()
{
  return vtkPolyData::SafeDownCast(this->GetOutputDataObject(1));
}

vtkPolyData* vtkGeodesicSource::GetPolylinesOutput()
{
  return vtkPolyData::SafeDownCast(this->GetOutputDataObject(2));
}

int vtkGeodesicSource::FillOutputPortInformation(int port, vtkInformation* info)
{
  info->Set(vtkDataObject::DATA_TYPE_NAME(), port == 0 ? "vtkImageData" : "vtkPolyData");
  return 1;
}

namespace
{
/// The first error a VTK reader (or its executive) reports, kept for the exception instead of
/// reaching the output window; warnings are silenced alike.
class ReaderMessages : public vtkCommand
{
public:
  static ReaderMessages* New() { return new ReaderMessages; }
  vtkTypeMacro(ReaderMessages, vtkCommand);
  void Execute(vtkObject*, unsigned long event, void* data) override
  {
    if (event != vtkCommand::ErrorEvent || !this->First.empty() || !data)
      return;
    // "ERROR: In FILE, line N\nClass (address): message\n": the message only.
    std::string text = static_cast<const char*>(data);
    const std::size_t at = text.find("): ");
    if (at != std::string::npos)
      text = text.substr(at + 3);
    this->First = text.substr(0, text.find('\n'));
    if (this->First.empty())
      this->First = "unknown error";
  }
  void Watch(vtkAlgorithm* algorithm)
  {
    for (vtkObject* o :
         { static_cast<vtkObject*>(algorithm), static_cast<vtkObject*>(algorithm->GetExecutive()) })
    {
      o->AddObserver(vtkCommand::ErrorEvent, this);
      o->AddObserver(vtkCommand::WarningEvent, this);
    }
  }
  std::string First;
};

/// An image through the VTK reader that recognises it; its declared size is checked (the reader's
/// information pass) before any pixel is read. Messages start with a verb, without the path.
asrt::ImagePixels readWithVtk(const std::string& path, const std::string& ext)
{
  vtkSmartPointer<vtkImageReader2> reader;
  reader.TakeReference(vtkImageReader2Factory::CreateImageReader2(path.c_str()));
  if (!reader)
    throw asrt::InvalidParameter("is not an image file any VTK reader recognises");
  // The factory also accepts readers that merely tolerate a file (HDR takes any "#" text), so the
  // file's extension must be one the chosen reader declares.
  const std::string declared = reader->GetFileExtensions() ? reader->GetFileExtensions() : "";
  if (ext.empty() || (" " + declared + " ").find(" " + ext + " ") == std::string::npos)
    throw asrt::InvalidParameter("is not an image file VTK can read (extension \"" + ext + "\", " +
                                 reader->GetClassName() + " reads \"" + declared + "\")");
  vtkNew<ReaderMessages> messages;
  messages->Watch(reader);
  reader->SetFileName(path.c_str());
  auto requireNoError = [&]()
  {
    if (!messages->First.empty() || reader->GetErrorCode() != 0)
      throw asrt::InvalidParameter("cannot be read" + (messages->First.empty()
                                                         ? std::string()
                                                         : " (" + messages->First + ")"));
  };
  reader->UpdateInformation();
  requireNoError();
  int extent[6];
  reader->GetOutputInformation(0)->Get(vtkStreamingDemandDrivenPipeline::WHOLE_EXTENT(), extent);
  const long long w = extent[1] - extent[0] + 1LL, h = extent[3] - extent[2] + 1LL,
                  slices = extent[5] - extent[4] + 1LL;
  if (slices != 1)
    throw asrt::InvalidParameter("declares " + std::to_string(slices) +
                                 " slices; an image texture is a single 2D image");
  // Peak: the reader's image and the RGB bytes made from it.
  const double bytesPerPixel = reader->GetNumberOfScalarComponents() *
                                 vtkDataArray::GetDataTypeSize(reader->GetDataScalarType()) +
                               3.0;
  asrt::checkTextureSize(w, h, bytesPerPixel);
  reader->Update();
  requireNoError();

  vtkImageData* img = reader->GetOutput();
  int dims[3];
  img->GetDimensions(dims);
  vtkDataArray* scalars = img->GetPointData()->GetScalars();
  if (!scalars || dims[0] != w || dims[1] != h)
    throw asrt::InvalidParameter("holds no pixels of its declared size");
  const int nc = scalars->GetNumberOfComponents();
  // 8-bit images pass through; wider integers are scaled from their type's range; floating-point
  // (HDR) images are taken as linear [0, 1] and clamped.
  const int type = scalars->GetDataType();
  const double scale = type == VTK_UNSIGNED_CHAR ? 1.0
                       : (type == VTK_FLOAT || type == VTK_DOUBLE)
                         ? 255.0
                         : 255.0 / scalars->GetDataTypeMax();
  asrt::ImagePixels px;
  px.width = dims[0];
  px.height = dims[1];
  px.rgb.resize(static_cast<size_t>(px.width) * px.height * 3);
  for (vtkIdType k = 0; k < static_cast<vtkIdType>(px.width) * px.height; ++k)
  {
    for (int c = 0; c < 3; ++c)
    {
      const int src = nc >= 3 ? c : 0; // grey (and grey + alpha) to RGB
      const double value = scalars->GetComponent(k, src) * scale;
      px.rgb[3 * k + c] = static_cast<unsigned char>(std::lround(std::clamp(value, 0.0, 255.0)));
    }
  }
  return px;
}
}

void vtkGeodesicSource::LoadImagePixels(const std::string& path, int& width, int& height,
                                        std::vector<unsigned char>& rgb)
{
  const std::string ext =
    path.find('.') == std::string::npos
      ? std::string()
      : vtksys::SystemTools::LowerCase(vtksys::SystemTools::GetFilenameLastExtension(path));
  asrt::ImagePixels px;
  try
  {
    // PNG and JPEG only: each is one file whose decoder fails on short data and whose size is
    // read from its header before any pixel is. Other formats VTK reads do not all do so (a
    // truncated PNM reads as black, a MetaImage names a second file that may be a FIFO).
    if (ext != ".png" && ext != ".jpg" && ext != ".jpeg")
      throw asrt::InvalidParameter(
        "is not a PNG or JPEG file (extension \"" + ext +
        "\"): image textures are PNG (.png) or JPEG (.jpg, .jpeg); convert other images first");
    asrt::requireTextureFile(path);
    // PNG through libpng, never vtkPNGReader (which crashes on a truncated file).
    px = ext == ".png" ? asrt::readPngTexture(path) : readWithVtk(path, ext);
  }
  catch (const asrt::InvalidParameter& e)
  {
    throw asrt::InvalidParameter("image file \"" + path + "\" " + e.what());
  }
  width = px.width;
  height = px.height;
  rgb = std::move(px.rgb);
}

struct vtkGeodesicSource::Internals
{
  /// The scene with this filter's overrides applied; its textures read through `loader` (the
  /// image files if empty).
  static asrt::SceneDescription Load(vtkGeodesicSource* self, asrt::ImageLoader loader = {})
  {
    asrt::SceneDescription d = asrt::loadScene(self->SceneText, self->SceneFileName,
                                               self->TextureDirectory, std::move(loader));
    if (self->OverrideSpacetime)
    {
      if (isSet(self->Mass))
        d.spacetime.mass = self->Mass;
      if (isSet(self->Spin))
        d.spacetime.spin = self->Spin;
      if (isSet(self->Charge))
        d.spacetime.charge = self->Charge;
    }
    auto override3 = [](const double* v, asrt::Vec3& target)
    {
      if (isSet(v[0]) || isSet(v[1]) || isSet(v[2]))
        target = asrt::Vec3(v[0], v[1], v[2]);
    };
    if (self->OverrideCamera)
    {
      override3(self->CameraPosition, d.camera.position);
      override3(self->FocalPoint, d.camera.focalPoint);
      override3(self->ViewUp, d.camera.viewUp);
      if (isSet(self->ViewAngle))
        d.camera.viewAngle = self->ViewAngle;
    }
    if (self->Resolution[0] != 0 || self->Resolution[1] != 0)
    {
      d.camera.width = self->Resolution[0];
      d.camera.height = self->Resolution[1];
    }
    if (self->IntegrationPreset && *self->IntegrationPreset)
    {
      try
      {
        d.integrator = asrt::integratorPreset(self->IntegrationPreset);
        d.rendering = asrt::renderingPreset(self->IntegrationPreset);
      }
      catch (const asrt::InvalidParameter& e)
      {
        throw asrt::InvalidParameter(std::string("integrator.preset: ") + e.what());
      }
    }
    if (self->IntegrationMethod && *self->IntegrationMethod)
      d.integrator.method = self->IntegrationMethod;
    if (self->OverrideIntegrationStep && isSet(self->IntegrationStep))
      d.integrator.step = self->IntegrationStep;
    if (self->Antialias && *self->Antialias)
    {
      try
      {
        d.rendering.mode = asrt::antialiasModeFromString(self->Antialias);
      }
      catch (const asrt::InvalidParameter& e)
      {
        throw asrt::InvalidParameter(std::string("rendering.antialias: ") + e.what());
      }
    }
    if (self->MaxRaysPerPixel != 0)
      d.rendering.maxRaysPerPixel = self->MaxRaysPerPixel;
    if (self->Supersample != 0)
      d.rendering.supersample = self->Supersample;
    if (self->GridLattice != 0)
      d.rendering.gridLattice = self->GridLattice;
    if (!std::isnan(self->GridTolerance))
      d.rendering.gridTolerance = self->GridTolerance;
    // The overridden values pass the scene file's own checks: a frame the file could not describe
    // is refused (a camera outside its celestial sphere, a mass whose horizon overflows, ...).
    asrt::validateScene(d);
    // The frame records the method actually used, so that stored frames stay identified by what
    // traced them even if the default changes.
    if (d.integrator.method == "auto")
      d.integrator.method = asrt::defaultMethod(*asrt::makeSpacetime(d.spacetime));
    // A frame of only some pixels is a frame of its own (see SetPixelSubset).
    d.subset = asrt::PixelSubsetId();
    if (self->PixelSubset)
    {
      std::vector<std::pair<int, int>> pixels;
      pixels.reserve(static_cast<size_t>(self->PixelSubset->GetNumberOfTuples()));
      for (vtkIdType k = 0; k < self->PixelSubset->GetNumberOfTuples(); ++k)
        pixels.emplace_back(self->PixelSubset->GetTypedComponent(k, 0),
                            self->PixelSubset->GetNumberOfComponents() > 1
                              ? self->PixelSubset->GetTypedComponent(k, 1)
                              : 0);
      d.subset = asrt::pixelSubsetId(std::move(pixels));
    }
    return d;
  }

  /// Traces rows [rowBegin, rowEnd) of the frame into the image and the hit points: the pixel
  /// subset's among them, or all of them; false if the filter was aborted (the outputs are then
  /// incomplete).
  static bool Trace(vtkGeodesicSource* self, const asrt::FrameTracer& tracer, int rowBegin,
                    int rowEnd, vtkImageData* image, vtkPolyData* hits)
  {
    const int W = tracer.description().camera.width, H = tracer.description().camera.height;
    auto progress = [self](double f)
    {
      self->UpdateProgress(0.95 * f);
      return !self->GetAbortExecute();
    };
    bool aborted = false;
    if (self->PixelSubset)
    {
      std::vector<std::pair<int, int>> subset;
      for (vtkIdType k = 0; k < self->PixelSubset->GetNumberOfTuples(); ++k)
      {
        const int i = self->PixelSubset->GetTypedComponent(k, 0);
        const int j = self->PixelSubset->GetTypedComponent(k, 1);
        if (i < 0 || i >= W || j < 0 || j >= H)
        {
          std::ostringstream os;
          os << "pixel subset entry " << k << " = (" << i << ", " << j << ") lies outside the " << W
             << " x " << H << " frame";
          throw asrt::InvalidParameter(os.str());
        }
        if (j >= rowBegin && j < rowEnd)
          subset.emplace_back(i, j);
      }
      const std::vector<asrt::RayRecord> records = tracer.tracePixels(subset, progress);
      aborted = self->GetAbortExecute();
      if (!aborted)
      {
        asrt::recordsToImage(records, W, rowBegin, rowEnd, image);
        if (self->GenerateHitPoints)
          asrt::recordsToPolyData(records, hits);
      }
    }
    else
    {
      // The records of a band go into the outputs as soon as they are finished: a frame's
      // records are never all held beside the arrays made of them.
      asrt::RowsBuilder outputs(image, self->GenerateHitPoints ? hits : nullptr, W, rowBegin,
                                rowEnd);
      const bool traced = asrt::traceRowsInBands(
        tracer, rowBegin, rowEnd,
        [&](const asrt::RayRecord* records, std::size_t count) { outputs.add(records, count); },
        progress);
      aborted = !traced || self->GetAbortExecute();
      if (!aborted)
        outputs.finish();
    }
    return !aborted;
  }
};

std::string vtkGeodesicSource::GetFrameSceneText()
{
  try
  {
    return asrt::effectiveSceneText(Internals::Load(this));
  }
  catch (const std::exception& e)
  {
    vtkErrorMacro(<< e.what());
    return std::string();
  }
}

std::string vtkGeodesicSource::GetFrameSceneTextWithoutImages()
{
  try
  {
    return asrt::effectiveSceneText(Internals::Load(this, asrt::neutralImageLoader()));
  }
  catch (const std::exception& e)
  {
    vtkErrorMacro(<< e.what());
    return std::string();
  }
}

bool vtkGeodesicSource::CountRayEnds(vtkImageData* frame, vtkIdType counts[3])
{
  counts[0] = counts[1] = counts[2] = 0;
  vtkDataArray* ends = frame ? frame->GetPointData()->GetArray("Termination") : nullptr;
  if (!ends || ends->GetNumberOfComponents() != 1)
    return false;
  for (vtkIdType k = 0; k < ends->GetNumberOfTuples(); ++k)
  {
    const auto end = static_cast<asrt::Termination>(static_cast<int>(ends->GetComponent(k, 0)));
    if (end == asrt::Termination::Running)
      continue; // not traced
    ++counts[0];
    if (end == asrt::Termination::NumericalFailure)
      ++counts[1];
    else if (end == asrt::Termination::StepBudget)
      ++counts[2];
  }
  return true;
}

int vtkGeodesicSource::RequestInformation(vtkInformation*, vtkInformationVector**,
                                          vtkInformationVector* outputVector)
{
  asrt::SceneDescription d;
  try
  {
    d = Internals::Load(this);
    this->Cache = std::make_shared<asrt::SceneDescription>(d);
    this->CacheTime = this->GetMTime();
  }
  catch (const std::exception& e)
  {
    vtkErrorMacro(<< e.what());
    // RequestData will not run: empty the outputs here, so that no stale frame survives an error.
    this->Cache.reset();
    for (int port = 0; port < 3; ++port)
      if (vtkDataObject* out = vtkDataObject::GetData(outputVector, port))
        out->Initialize();
    return 0;
  }
  const int ext[6] = { 0, d.camera.width - 1, 0, d.camera.height - 1, 0, 0 };
  const double spacing[3] = { 1, 1, 1 }, origin[3] = { 0, 0, 0 };
  vtkInformation* image = outputVector->GetInformationObject(0);
  image->Set(vtkStreamingDemandDrivenPipeline::WHOLE_EXTENT(), ext, 6);
  image->Set(vtkDataObject::SPACING(), spacing, 3);
  image->Set(vtkDataObject::ORIGIN(), origin, 3);
  vtkDataObject::SetPointDataActiveScalarInfo(image, VTK_UNSIGNED_CHAR, 3);
  image->Set(vtkAlgorithm::CAN_PRODUCE_SUB_EXTENT(), 1);
  for (int port = 0; port < 3; ++port)
    outputVector->GetInformationObject(port)->Set(CAN_HANDLE_PIECE_REQUEST(), 1);
  return 1;
}

int vtkGeodesicSource::RequestData(vtkInformation*, vtkInformationVector**,
                                   vtkInformationVector* outputVector)
{
  vtkInformation* imageInfo = outputVector->GetInformationObject(0);
  vtkImageData* image = vtkImageData::GetData(outputVector, 0);
  vtkPolyData* hits = vtkPolyData::GetData(outputVector, 1);
  vtkPolyData* lines = vtkPolyData::GetData(outputVector, 2);
  try
  {
    // The scene (and its textures) as RequestInformation loaded it, unless something changed since.
    const asrt::SceneDescription d =
      this->Cache && this->CacheTime == this->GetMTime() ? *this->Cache : Internals::Load(this);
    const asrt::FrameTracer tracer(d);
    const int W = d.camera.width, H = d.camera.height;

    // Pieces are bands of whole rows.
    int piece = 0, pieces = 1;
    if (imageInfo->Has(vtkStreamingDemandDrivenPipeline::UPDATE_PIECE_NUMBER()))
      piece = imageInfo->Get(vtkStreamingDemandDrivenPipeline::UPDATE_PIECE_NUMBER());
    if (imageInfo->Has(vtkStreamingDemandDrivenPipeline::UPDATE_NUMBER_OF_PIECES()))
      pieces =
        std::max(1, imageInfo->Get(vtkStreamingDemandDrivenPipeline::UPDATE_NUMBER_OF_PIECES()));
    int rowBegin = static_cast<int>(static_cast<long long>(H) * piece / pieces);
    int rowEnd = static_cast<int>(static_cast<long long>(H) * (piece + 1) / pieces);
    if (pieces == 1 && imageInfo->Has(vtkStreamingDemandDrivenPipeline::UPDATE_EXTENT()))
    {
      // A sub-extent request: trace just its rows (whole rows, as pieces are).
      int ue[6];
      imageInfo->Get(vtkStreamingDemandDrivenPipeline::UPDATE_EXTENT(), ue);
      rowBegin = std::clamp(ue[2], 0, H);
      rowEnd = std::clamp(ue[3] + 1, rowBegin, H);
    }

    // Whole rows are traced a band at a time (asrt::traceRowsInBands), a subset's records all
    // together.
    const double pixels = static_cast<double>(W) * (rowEnd - rowBegin);
    const double bytes =
      pixels * kOutputBytesPerPixel +
      (this->PixelSubset ? pixels : static_cast<double>(asrt::kBandPixels + 2 * W)) *
        sizeof(asrt::RayRecord);
    const double limit = this->MemoryLimit > 0.0 ? this->MemoryLimit : 0.8 * physicalMemory();
    if (bytes > limit)
    {
      std::ostringstream os;
      os << "a " << W << " x " << H << " frame needs about " << bytes / 1e9 << " GB, more than the "
         << limit / 1e9 << " GB allowed";
      throw asrt::InvalidParameter(os.str());
    }
    if (this->GeneratePolylines)
    {
      // Every s-th column, and the rows of this band that are multiples of s.
      const long long s = this->PolylineStride;
      const long long rays = this->PolylinePixels
                               ? this->PolylinePixels->GetNumberOfTuples()
                               : (W + s - 1) / s * ((rowEnd + s - 1) / s - (rowBegin + s - 1) / s);
      if (rays > kMaxPolylines)
        throw asrt::InvalidParameter(
          std::to_string(rays) + " rays asked for as polylines; at most " +
          std::to_string(kMaxPolylines) + " are drawn (choose a larger stride or fewer pixels)");
    }

    auto requirePairs = [](vtkIntArray* a, const char* what)
    {
      if (a && a->GetNumberOfComponents() != 2)
      {
        std::ostringstream os;
        os << what << " must have 2 components (i, j), has " << a->GetNumberOfComponents();
        throw asrt::InvalidParameter(os.str());
      }
    };
    requirePairs(this->PixelSubset, "PixelSubset");
    requirePairs(this->PolylinePixels, "PolylinePixels");
    if (!this->GenerateHitPoints)
      hits->Initialize(); // no points of an earlier run stay behind
    if (!Internals::Trace(this, tracer, rowBegin, rowEnd, image, hits))
    {
      asrt::reportAbort(this);
      image->Initialize();
      hits->Initialize();
      lines->Initialize();
      return 1;
    }

    // The frame's parameters travel with the hits, for the writer and for readers of the data.
    asrt::setFrameFieldData(d, hits->GetFieldData());

    // Port 2: polylines of chosen rays.
    lines->Initialize();
    if (this->GeneratePolylines)
    {
      std::vector<std::pair<int, int>> chosen;
      if (this->PolylinePixels)
      {
        for (vtkIdType k = 0; k < this->PolylinePixels->GetNumberOfTuples(); ++k)
        {
          const int i = this->PolylinePixels->GetTypedComponent(k, 0);
          const int j = this->PolylinePixels->GetTypedComponent(k, 1);
          if (i < 0 || i >= W || j < 0 || j >= H)
          {
            std::ostringstream os;
            os << "polyline pixel entry " << k << " = (" << i << ", " << j << ") lies outside the "
               << W << " x " << H << " frame";
            throw asrt::InvalidParameter(os.str());
          }
          if (j >= rowBegin && j < rowEnd)
            chosen.emplace_back(i, j);
        }
      }
      else
      {
        const int s = this->PolylineStride;
        for (int j = rowBegin + (s - rowBegin % s) % s; j < rowEnd; j += s)
          for (int i = 0; i < W; i += s)
            chosen.emplace_back(i, j);
      }
      std::vector<asrt::RayPath> paths(chosen.size());
      for (std::size_t k = 0; k < chosen.size(); ++k)
      {
        asrt::RayPath& p = paths[k];
        std::tie(p.i, p.j) = chosen[k];
        p.termination = tracer.tracePixel(p.i, p.j, &p.points).termination;
      }
      asrt::pathsToPolyData(paths, lines);
    }
    this->UpdateProgress(1.0);
  }
  catch (const std::exception& e)
  {
    vtkErrorMacro(<< e.what());
    image->Initialize();
    hits->Initialize();
    lines->Initialize();
    return 0;
  }
  return 1;
}

void vtkGeodesicSource::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "SceneFileName: " << (this->SceneFileName ? this->SceneFileName : "(none)")
     << "\n";
  os << indent << "SceneText: " << (this->SceneText ? "(set)" : "(none)") << "\n";
  os << indent << "TextureDirectory: "
     << (this->TextureDirectory ? this->TextureDirectory : "(working directory)") << "\n";
  os << indent << "OverrideSpacetime: " << this->OverrideSpacetime << "\n";
  os << indent << "Mass: " << this->Mass << "\n";
  os << indent << "Spin: " << this->Spin << "\n";
  os << indent << "Charge: " << this->Charge << "\n";
  os << indent << "OverrideCamera: " << this->OverrideCamera << "\n";
  os << indent << "CameraPosition: " << this->CameraPosition[0] << " " << this->CameraPosition[1]
     << " " << this->CameraPosition[2] << "\n";
  os << indent << "FocalPoint: " << this->FocalPoint[0] << " " << this->FocalPoint[1] << " "
     << this->FocalPoint[2] << "\n";
  os << indent << "ViewUp: " << this->ViewUp[0] << " " << this->ViewUp[1] << " " << this->ViewUp[2]
     << "\n";
  os << indent << "ViewAngle: " << this->ViewAngle << "\n";
  os << indent << "Resolution: " << this->Resolution[0] << " " << this->Resolution[1] << "\n";
  os << indent << "GenerateHitPoints: " << this->GenerateHitPoints << "\n";
  os << indent
     << "IntegrationMethod: " << (this->IntegrationMethod ? this->IntegrationMethod : "(scene)")
     << "\n";
  os << indent
     << "IntegrationPreset: " << (this->IntegrationPreset ? this->IntegrationPreset : "(scene)")
     << "\n"
     << indent << "Antialias: " << (this->Antialias ? this->Antialias : "(scene)") << "\n"
     << indent << "MaxRaysPerPixel: " << this->MaxRaysPerPixel << "\n"
     << indent << "Supersample: " << this->Supersample << "\n"
     << indent << "GridLattice: " << this->GridLattice << "\n"
     << indent << "GridTolerance: " << this->GridTolerance << "\n";
  os << indent << "OverrideIntegrationStep: " << this->OverrideIntegrationStep << "\n";
  os << indent << "IntegrationStep: " << this->IntegrationStep << "\n";
  os << indent << "PixelSubset: " << (this->PixelSubset ? "set" : "(none)") << "\n";
  os << indent << "GeneratePolylines: " << this->GeneratePolylines << "\n";
  os << indent << "PolylineStride: " << this->PolylineStride << "\n";
  os << indent << "MemoryLimit: " << this->MemoryLimit << "\n";
}
