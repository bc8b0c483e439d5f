/**
 * @class   vtkGeodesicPostgreSQLWriter
 * @brief   accumulates a traced frame in PostgreSQL
 *
 * Input port 0: the hit points of vtkGeodesicSource (its port 1): one vertex per ray with the ray
 * records as point data (hit points without "RaysPerPixel", made before anti-aliasing, are
 * stored with one ray a pixel) and the frame's effective scene as field data. Input port 1,
 * optional: the source's polylines (its port 2), stored with the frame, one per pixel, bit-exact
 * (vtkGeodesicPostgreSQLReader gives them back on its port 2). The frame, and its polylines if
 * connected, are written in one transaction with binary COPY (asrt::RayStore): wholly stored or
 * not at all. The same scene with the same parameters is the same frame; writing it again is an
 * error unless ReplaceExisting is on. Malformed polylines (missing arrays, cells that are not
 * lines, two polylines of one pixel, a pixel outside the frame) are refused before anything is
 * written.
 *
 * Connection: a libpq conninfo string or URI in ConnectionString; empty uses the standard PG*
 * environment variables when any is set, and otherwise starts (or reuses) the private embedded
 * server (asrt::EmbeddedPostgres), so that nothing needs setting up.
 */
#ifndef vtkGeodesicPostgreSQLWriter_h
#define vtkGeodesicPostgreSQLWriter_h

#include "asrtFiltersModule.h" // for export macro
#include "vtkWriter.h"

#include <functional> // for the cancellation predicate

class ASRTFILTERS_EXPORT vtkGeodesicPostgreSQLWriter : public vtkWriter
{
public:
  static vtkGeodesicPostgreSQLWriter* New();
  vtkTypeMacro(vtkGeodesicPostgreSQLWriter, vtkWriter);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  ///@{
  /// libpq conninfo or URI; empty: PG* variables if set, else the embedded server.
  vtkSetStringMacro(ConnectionString);
  vtkGetStringMacro(ConnectionString);
  ///@}

  ///@{
  /// A free-form label stored with the frame (bound as a parameter: any valid UTF-8 is safe).
  vtkSetStringMacro(Label);
  vtkGetStringMacro(Label);
  ///@}

  ///@{
  /// Replace a stored frame of the same scene and parameters instead of refusing.
  vtkSetMacro(ReplaceExisting, bool);
  vtkGetMacro(ReplaceExisting, bool);
  vtkBooleanMacro(ReplaceExisting, bool);
  ///@}

  /// Id of the frame the last successful Write() stored, −1 before.
  vtkGetMacro(FrameId, vtkIdType);

#ifndef __VTK_WRAP__
  /// Asked again and again, from another thread, while the frame is being stored: once it returns
  /// true, the write is cancelled on the server (a wait for a lock included) and rolled back,
  /// with an error and nothing stored (asrt::FrameWriteOptions::cancelled). Unset: never.
  void SetCancelRequested(std::function<bool()> cancelled);
#endif

protected:
  vtkGeodesicPostgreSQLWriter();
  ~vtkGeodesicPostgreSQLWriter() override;
  void WriteData() override;
  int FillInputPortInformation(int port, vtkInformation* info) override;

  char* ConnectionString = nullptr;
  char* Label = nullptr;
  bool ReplaceExisting = false;
  vtkIdType FrameId = -1;
  std::function<bool()> CancelRequested;

private:
  vtkGeodesicPostgreSQLWriter(const vtkGeodesicPostgreSQLWriter&) = delete;
  void operator=(const vtkGeodesicPostgreSQLWriter&) = delete;
};

#endif
