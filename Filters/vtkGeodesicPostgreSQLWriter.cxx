#include "vtkGeodesicPostgreSQLWriter.h"

#include "GeodesicRecordArrays.h"
#include "RayStore.h"
#include "StoreConnection.h"

#include "vtkInformation.h"
#include "vtkObjectFactory.h"
#include "vtkPolyData.h"

vtkStandardNewMacro(vtkGeodesicPostgreSQLWriter);

vtkGeodesicPostgreSQLWriter::vtkGeodesicPostgreSQLWriter()
{
  this->SetNumberOfInputPorts(2);
}

vtkGeodesicPostgreSQLWriter::~vtkGeodesicPostgreSQLWriter()
{
  this->SetConnectionString(nullptr);
  this->SetLabel(nullptr);
}

int vtkGeodesicPostgreSQLWriter::FillInputPortInformation(int port, vtkInformation* info)
{
  info->Set(vtkAlgorithm::INPUT_REQUIRED_DATA_TYPE(), "vtkPolyData");
  if (port == 1)
    info->Set(vtkAlgorithm::INPUT_IS_OPTIONAL(), 1);
  return 1;
}

void vtkGeodesicPostgreSQLWriter::WriteData()
{
  vtkPolyData* hits = vtkPolyData::SafeDownCast(this->GetInput());
  try
  {
    if (!hits || hits->GetNumberOfPoints() == 0)
      throw asrt::InvalidParameter("nothing to write: the input has no hit points");
    const asrt::SceneDescription frame = asrt::frameFromFieldData(hits->GetFieldData());
    // Read from the arrays as the COPY streams them, on each of its connections: the frame's
    // records are never all in memory beside the hit points.
    const asrt::HitPointRecords records(hits);
    std::vector<asrt::RayPath> paths;
    if (this->GetNumberOfInputConnections(1) > 0)
    {
      vtkPolyData* lines = vtkPolyData::SafeDownCast(this->GetInputDataObject(1, 0));
      if (!lines)
        throw asrt::InvalidParameter("the polylines input (port 1) is not poly data");
      paths = asrt::polyDataToPaths(lines);
    }
    this->UpdateProgress(0.1);
    asrt::RayStore store(asrt::storeConnection(this->ConnectionString));
    store.migrate();
    this->FrameId = static_cast<vtkIdType>(store.writeFrame(
      frame, this->Label ? this->Label : "", static_cast<std::size_t>(records.count()),
      [&records](std::size_t k, asrt::RayRecord& r) { records.read(static_cast<vtkIdType>(k), r); },
      asrt::FrameWriteOptions()
        .withPaths(std::move(paths))
        .replacing(this->ReplaceExisting)
        .cancelledWhen(this->CancelRequested)
        .fromConcurrentProducer()));
    this->UpdateProgress(1.0);
  }
  catch (const std::exception& e)
  {
    vtkErrorMacro(<< e.what());
  }
}

void vtkGeodesicPostgreSQLWriter::SetCancelRequested(std::function<bool()> cancelled)
{
  this->CancelRequested = std::move(cancelled);
}

void vtkGeodesicPostgreSQLWriter::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "ConnectionString: "
     << (this->ConnectionString && *this->ConnectionString ? "(set)" : "(default)") << "\n";
  os << indent << "Label: " << (this->Label ? this->Label : "") << "\n";
  os << indent << "ReplaceExisting: " << this->ReplaceExisting << "\n";
  os << indent << "FrameId: " << this->FrameId << "\n";
}
