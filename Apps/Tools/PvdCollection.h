// ParaView's time-series collection file (.pvd): a tiny XML list of the VTK XML files of a series,
// one <DataSet timestep=".." part=".." file=".."/> per file, that ParaView opens as one source with
// a time axis. Used by `asrt trace --sweep/--orbit` and wherever a series of frames is written.
#ifndef asrt_tools_PvdCollection_h
#define asrt_tools_PvdCollection_h

#include <string>
#include <vector>

namespace asrt
{
namespace tools
{
class TemporaryFile;

class PvdCollection
{
public:
  /// Adds a file at a time step. `part` distinguishes several files of one step (ParaView shows
  /// them as blocks of one dataset); one series per .pvd file needs only part 0.
  void add(double timestep, const std::string& file, int part = 0);

  std::size_t size() const { return this->Entries.size(); }

  /// Writes the collection to `pvdPath` (whole or not at all: a temporary file renamed into
  /// place). Files inside the .pvd's directory are listed relative to it, so the folder can be
  /// moved; others keep their path. Throws std::runtime_error if it cannot be written.
  void write(const std::string& pvdPath) const;
  /// The same into a member of an AtomicFileSet (in place when the set is committed).
  void write(TemporaryFile& file) const;

private:
  struct Entry
  {
    double timestep;
    int part;
    std::string file;
  };
  std::vector<Entry> Entries;
};
}
}

#endif
