#include "vtkGeodesicPostgreSQLReader.h"

#include "GeodesicRecordArrays.h"
#include "RayStore.h"
#include "SceneFile.h"
#include "StoreConnection.h"

#include "vtkImageData.h"
#include "vtkInformation.h"
#include "vtkInformationVector.h"
#include "vtkObjectFactory.h"
#include "vtkPolyData.h"
#include "vtkStreamingDemandDrivenPipeline.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <set>
#include <sstream>
#include <utility>

vtkStandardNewMacro(vtkGeodesicPostgreSQLReader);

namespace
{
/// The reader's limits on the statements of its store.
void limitReads(asrt::RayStore& store, double lockTimeout, const std::function<bool()>& cancelled)
{
  // Whole milliseconds; a positive time never becomes 0, which would mean no limit at all.
  store.setReadLockTimeout(std::chrono::milliseconds(
    std::max(std::llround(lockTimeout * 1000), lockTimeout > 0 ? 1LL : 0LL)));
  store.setReadCancellation(cancelled);
}

/// Bytes a pixel of the image takes (RGB colours, object id, image order, path length,
/// termination, rays a pixel), and a ray once read (its record, then its hit point with every
/// field as point data and its vertex), rounded up.
constexpr double kImageBytesPerPixel = 28.0;
constexpr double kBytesPerRay = sizeof(asrt::RayRecord) + 280.0;

/// Refuses a frame whose outputs, sized from its row, would need more than `limit` bytes (0: the
/// store's default limit).
void requireMemory(const asrt::FrameInfo& f, double limit)
{
  const double bytes = static_cast<double>(f.key.width) * f.key.height * kImageBytesPerPixel +
                       static_cast<double>(f.rayCount) * kBytesPerRay;
  const double allowed = limit > 0.0 ? limit : asrt::defaultMemoryLimit();
  if (bytes > allowed)
  {
    std::ostringstream os;
    os << "frame " << f.id << " (" << f.key.width << " x " << f.key.height << " pixels, "
       << f.rayCount << " rays) needs about " << bytes / 1e9 << " GB to read, more than the "
       << allowed / 1e9 << " GB allowed";
    throw asrt::InvalidParameter(os.str());
  }
}
}

vtkGeodesicPostgreSQLReader::vtkGeodesicPostgreSQLReader()
{
  this->SetNumberOfInputPorts(0);
  this->SetNumberOfOutputPorts(3);
}

vtkGeodesicPostgreSQLReader::~vtkGeodesicPostgreSQLReader()
{
  this->SetConnectionString(nullptr);
  this->SetPredicate(nullptr);
}

vtkImageData* vtkGeodesicPostgreSQLReader::GetImageOutput()
{
  return vtkImageData::SafeDownCast(this->GetOutputDataObject(0));
}

vtkPolyData* vtkGeodesicPostgreSQLReader::GetHitsOutput()
{
  return vtkPolyData::SafeDownCast(this->GetOutputDataObject(1));
}

vtkPolyData* vtkGeodesicPostgreSQLReader::GetPolylinesOutput()
{
  return vtkPolyData::SafeDownCast(this->GetOutputDataObject(2));
}

int vtkGeodesicPostgreSQLReader::FillOutputPortInformation(int port, vtkInformation* info)
{
  info->Set(vtkDataObject::DATA_TYPE_NAME(), port == 0 ? "vtkImageData" : "vtkPolyData");
  return 1;
}

int vtkGeodesicPostgreSQLReader::RequestInformation(vtkInformation*, vtkInformationVector**,
                                                    vtkInformationVector* outputVector)
{
  this->FrameIds.clear();
  this->FrameDescriptions.clear();
  this->ResolvedFrame = -1;
  try
  {
    asrt::RayStore store(asrt::storeConnection(this->ConnectionString));
    limitReads(store, this->LockTimeout, this->CancelRequested);
    // A reader upgrades an older ASRT schema but creates none in a database that has none.
    store.upgrade();
    const std::vector<asrt::FrameInfo> frames = store.listFrames();
    for (const asrt::FrameInfo& f : frames)
    {
      this->FrameIds.push_back(static_cast<vtkIdType>(f.id));
      std::ostringstream os;
      os << "frame " << f.id << ": " << f.name << " [" << f.label << "] M=" << f.key.spacetime.mass
         << " a=" << f.key.spacetime.spin << " " << f.key.width << "x" << f.key.height << " "
         << f.key.method << ", " << f.rayCount << " rays, " << f.createdAt;
      this->FrameDescriptions.push_back(os.str());
    }
    if (frames.empty())
      throw asrt::InvalidParameter("the database holds no frames");
    const asrt::FrameInfo* chosen = &frames.back(); // the most recent
    if (this->FrameId >= 0)
    {
      chosen = nullptr;
      for (const asrt::FrameInfo& f : frames)
        if (f.id == this->FrameId)
          chosen = &f;
      if (!chosen)
      {
        std::ostringstream os;
        os << "no stored frame " << this->FrameId << " (" << frames.size() << " frames listed)";
        throw asrt::InvalidParameter(os.str());
      }
    }
    // The extents below, and RequestData's arrays, are sized from the frame's row.
    asrt::checkFrameSize(*chosen);
    requireMemory(*chosen, this->MemoryLimit);
    this->ResolvedFrame = static_cast<vtkIdType>(chosen->id);
    this->Width = chosen->key.width;
    this->Height = chosen->key.height;
  }
  catch (const std::exception& e)
  {
    vtkErrorMacro(<< e.what());
    for (int port = 0; port < this->GetNumberOfOutputPorts(); ++port)
      if (vtkDataObject* out = vtkDataObject::GetData(outputVector, port))
        out->Initialize();
    return 0;
  }
  const int ext[6] = { 0, this->Width - 1, 0, this->Height - 1, 0, 0 };
  vtkInformation* image = outputVector->GetInformationObject(0);
  image->Set(vtkStreamingDemandDrivenPipeline::WHOLE_EXTENT(), ext, 6);
  const double spacing[3] = { 1, 1, 1 }, origin[3] = { 0, 0, 0 };
  image->Set(vtkDataObject::SPACING(), spacing, 3);
  image->Set(vtkDataObject::ORIGIN(), origin, 3);
  vtkDataObject::SetPointDataActiveScalarInfo(image, VTK_UNSIGNED_CHAR, 3);
  return 1;
}

int vtkGeodesicPostgreSQLReader::RequestData(vtkInformation*, vtkInformationVector**,
                                             vtkInformationVector* outputVector)
{
  vtkImageData* image = vtkImageData::GetData(outputVector, 0);
  vtkPolyData* hits = vtkPolyData::GetData(outputVector, 1);
  vtkPolyData* lines = vtkPolyData::GetData(outputVector, 2);
  try
  {
    asrt::RayStore store(asrt::storeConnection(this->ConnectionString));
    store.setMemoryLimit(this->MemoryLimit);
    limitReads(store, this->LockTimeout, this->CancelRequested);
    const std::vector<asrt::RayRecord> records =
      store.readFrame(this->ResolvedFrame, this->Predicate ? this->Predicate : "");
    this->UpdateProgress(0.7);
    std::vector<asrt::RayPath> paths = store.readPaths(this->ResolvedFrame);
    if (this->Predicate && *this->Predicate)
    {
      std::set<std::pair<int, int>> selected;
      for (const asrt::RayRecord& r : records)
        selected.insert({ r.i, r.j });
      paths.erase(std::remove_if(paths.begin(), paths.end(),
                                 [&](const asrt::RayPath& p) {
                                   return selected.count({ p.i, p.j }) == 0;
                                 }),
                  paths.end());
    }
    this->UpdateProgress(0.8);
    asrt::recordsToImage(records, this->Width, 0, this->Height, image);
    asrt::recordsToPolyData(records, hits);
    asrt::pathsToPolyData(paths, lines);
    auto frame = asrt::parseSceneWithoutImages(store.frameSceneText(this->ResolvedFrame));
    asrt::setFrameFieldData(frame, hits->GetFieldData());
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

void vtkGeodesicPostgreSQLReader::SetCancelRequested(std::function<bool()> cancelled)
{
  this->CancelRequested = std::move(cancelled);
}

void vtkGeodesicPostgreSQLReader::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "ConnectionString: "
     << (this->ConnectionString && *this->ConnectionString ? "(set)" : "(default)") << "\n";
  os << indent << "FrameId: " << this->FrameId << "\n";
  os << indent << "MemoryLimit: " << this->MemoryLimit << "\n";
  os << indent << "Predicate: " << (this->Predicate ? this->Predicate : "") << "\n";
  os << indent << "LockTimeout: " << this->LockTimeout << " s\n";
  os << indent << "Frames listed: " << this->FrameIds.size() << "\n";
}
