/**
 * @class   vtkGeodesicPostgreSQLReader
 * @brief   reads an accumulated frame back from PostgreSQL
 *
 * RequestInformation lists the stored frames (GetNumberOfFrames, GetFrameIdAt,
 * GetFrameDescription). RequestData reads the frame FrameId back as vtkGeodesicSource's outputs:
 * port 0 the image, shaded again from the stored colours (with "RaysPerPixel" among its arrays),
 * port 1 the hit points with every record field, bit-exact for doubles, and the frame's scene as
 * field data, port 2 the polylines stored with the frame (empty if none), bit-exact. An optional
 * Predicate over the columns of the view rays_v (e.g. "object_id = 2 AND image_order = 1")
 * selects a subset of rays: an expression of the grammar in RayPredicate.h (columns, constants,
 * arithmetic, comparisons, AND/OR/NOT and a few math functions; anything else is refused before
 * it reaches the server), evaluated by the server in a read-only transaction with the rights of
 * the role asrt_predicate alone (asrt::RayStore::readFrame); port 2 then holds the polylines of
 * the selected rays' pixels only.
 * Connection as for vtkGeodesicPostgreSQLWriter; a database without an ASRT schema is an error
 * (the reader creates none), an older schema is upgraded. A table that another session holds
 * locked is waited for at most LockTimeout seconds, and the reading can be cancelled
 * (SetCancelRequested), a wait for a lock included.
 */
#ifndef vtkGeodesicPostgreSQLReader_h
#define vtkGeodesicPostgreSQLReader_h

#include "asrtFiltersModule.h" // for export macro
#include "vtkImageAlgorithm.h"

#include <cstdint>    // for std::int64_t
#include <functional> // for the cancellation predicate
#include <string>     // for std::string
#include <vector>     // for std::vector

class vtkImageData;
class vtkPolyData;

class ASRTFILTERS_EXPORT vtkGeodesicPostgreSQLReader : public vtkImageAlgorithm
{
public:
  static vtkGeodesicPostgreSQLReader* New();
  vtkTypeMacro(vtkGeodesicPostgreSQLReader, vtkImageAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  ///@{
  vtkSetStringMacro(ConnectionString);
  vtkGetStringMacro(ConnectionString);
  ///@}

  ///@{
  /// The frame to read; −1 (default) reads the most recently stored one.
  vtkSetMacro(FrameId, vtkIdType);
  vtkGetMacro(FrameId, vtkIdType);
  ///@}

  ///@{
  /// Boolean expression over rays_v selecting the rays to read (asrt::rayPredicateSql's
  /// grammar); empty reads them all.
  vtkSetStringMacro(Predicate);
  vtkGetStringMacro(Predicate);
  ///@}

  ///@{
  /// Memory the frame's outputs may use, in bytes; 0 (default) allows 80 % of this machine's
  /// memory, as vtkGeodesicSource does. A stored frame whose size (as its row in frames says)
  /// would need more, or that asrt::checkFrameSize refuses, is an error before anything is
  /// allocated.
  vtkSetMacro(MemoryLimit, double);
  vtkGetMacro(MemoryLimit, double);
  ///@}

  /// The frames listed by the last RequestInformation (call UpdateInformation()).
  int GetNumberOfFrames() const { return static_cast<int>(this->FrameIds.size()); }
  vtkIdType GetFrameIdAt(int k) const { return this->FrameIds.at(k); }
  const char* GetFrameDescription(int k) const { return this->FrameDescriptions.at(k).c_str(); }

  vtkImageData* GetImageOutput();
  vtkPolyData* GetHitsOutput();
  vtkPolyData* GetPolylinesOutput();

  ///@{
  /// How long, in seconds, each statement of the reading waits for a lock that another session
  /// holds before the reading fails with an error naming the locked table; 0 waits as long as the
  /// lock is held. Default 30 (asrt::RayStore::kDefaultReadLockTimeout).
  vtkSetClampMacro(LockTimeout, double, 0.0, 2147483.0);
  vtkGetMacro(LockTimeout, double);
  ///@}

#ifndef __VTK_WRAP__
  /// Asked again and again, from another thread, while the frames are listed or read: once it
  /// returns true, the statement under way is cancelled on the server (a wait for a lock
  /// included), with an error and no output (asrt::RayStore::setReadCancellation). Unset: never.
  void SetCancelRequested(std::function<bool()> cancelled);
#endif

protected:
  vtkGeodesicPostgreSQLReader();
  ~vtkGeodesicPostgreSQLReader() override;
  int FillOutputPortInformation(int port, vtkInformation* info) override;
  int RequestInformation(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;

  char* ConnectionString = nullptr;
  char* Predicate = nullptr;
  vtkIdType FrameId = -1;
  double LockTimeout = 30;
  std::function<bool()> CancelRequested;
  std::vector<vtkIdType> FrameIds;
  std::vector<std::string> FrameDescriptions;
  double MemoryLimit = 0.0;
  vtkIdType ResolvedFrame = -1;
  int Width = 0, Height = 0;

private:
  vtkGeodesicPostgreSQLReader(const vtkGeodesicPostgreSQLReader&) = delete;
  void operator=(const vtkGeodesicPostgreSQLReader&) = delete;
};

#endif
