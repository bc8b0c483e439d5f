#include "vtkGeodesicPostgreSQLWriter.h"

#include "GeodesicRecordArrays.h"
#include "StoreConnection.h"
#include "RayStore.h"

#include "vtkInformation.h"
#include "vtkObjectFactory.h"
#include "vtkPolyData.h"

vtkStandardNewMacro(vtkGeodesicPostgreSQLWriter);

vtkGeodesicPostgreSQLWriter::vtkGeodesicPostgreSQLWriter() = default;

vtkGeodesicPostgreSQLWriter::~vtkGeodesicPostgreSQLWriter()
{
  this->SetConnectionString(nullptr);
  this->SetLabel(nullptr);
}

int vtkGeodesicPostgreSQLWriter::FillInputPortInformation(int, vtkInformation* info)
{
  info->Set(vtkAlgorithm::INPUT_REQUIRED_DATA_TYPE(), "vtkPolyData");
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
    const std::vector<asrt::RayRecord> records = asrt::polyDataToRecords(hits);
    this->UpdateProgress(0.1);
    asrt::RayStore store(asrt::storeConnection(this->ConnectionString));
    store.migrate();
    this->FrameId = static_cast<vtkIdType>(
      store.writeFrame(frame, this->Label ? this->Label : "", records, this->ReplaceExisting));
    this->UpdateProgress(1.0);
  }
  catch (const std::exception& e)
  {
    vtkErrorMacro(<< e.what());
  }
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
