// The pieces every `asrt` subcommand shares: exit codes and the errors that choose them, the
// option parser, the scene overrides and the database connection.
#ifndef asrt_cli_Cli_h
#define asrt_cli_Cli_h

#include <chrono>
#include <cstdint>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

class vtkGeodesicPostgreSQLReader;
class vtkGeodesicSource;
class vtkImageData;
class vtkMultiProcessController;

namespace asrt
{
class RayStore;
struct RayRecord;

namespace cli
{
/// Exit codes, as `asrt --help` documents them.
enum ExitCode : int
{
  kOk = 0,
  kFailure = 1,      ///< the work failed: a file could not be written, too many rays failed, ...
  kUsage = 2,        ///< the command line is wrong: unknown option, missing or malformed value
  kDatabase = 3,     ///< the database: unreachable, refused, no such frame, duplicate frame
  kBadInput = 4,     ///< the scene or parameters: bad scene file, missing texture, camera inside
                     ///< the horizon, spin above the mass, ...
  kInterrupted = 130 ///< stopped by Ctrl-C (nothing half-written is left)
};
extern const char* const kExitCodeHelp;

struct UsageError : std::runtime_error
{
  using std::runtime_error::runtime_error;
};
struct InputError : std::runtime_error
{
  using std::runtime_error::runtime_error;
};
struct DatabaseError : std::runtime_error
{
  using std::runtime_error::runtime_error;
};
struct Interrupted : std::runtime_error
{
  Interrupted()
    : std::runtime_error("interrupted")
  {
  }
};

/// One option a subcommand accepts.
struct OptionSpec
{
  enum Kind
  {
    Flag,         ///< --name
    Value,        ///< --name VALUE or --name=VALUE (VALUE may start with '-')
    OptionalValue ///< --name or --name=VALUE
  };
  std::string name; ///< without the dashes
  Kind kind;
  char shortName = 0;
};

/// The parsed command line of one subcommand. Throws UsageError for an unknown option, a missing
/// value, or a value given to a flag.
class Options
{
public:
  Options(const std::vector<OptionSpec>& specs, const std::vector<std::string>& args);

  bool has(const std::string& name) const { return this->Values.count(name) > 0; }
  /// The value given last (an OptionalValue given bare has "").
  std::string get(const std::string& name, const std::string& fallback = std::string()) const;
  const std::vector<std::string>& positional() const { return this->Positional; }
  /// Throws UsageError unless there are between min and max positional arguments.
  void expectPositional(std::size_t min, std::size_t max, const char* what) const;
  bool help() const { return this->Help; }

  // Typed values of an option, checked: UsageError names the option and shows the value.
  std::optional<double> number(const std::string& name) const;
  std::optional<int> positiveInteger(const std::string& name) const;
  /// "x,y,z"
  std::optional<std::vector<double>> vector3(const std::string& name) const;
  /// "WxH"
  std::optional<std::pair<int, int>> size(const std::string& name) const;

private:
  std::map<std::string, std::string> Values;
  std::vector<std::string> Positional;
  bool Help = false;
};

/// Parsers for the typed values (also used for the parts of compound values).
/// `text` in single quotes as error messages show an argument: whole when short, else its first
/// kQuotedLength characters (cut at a character, not inside one) and its length, so that a huge
/// value makes a line, not a page.
constexpr std::size_t kQuotedLength = 60;
std::string quotedArgument(const std::string& text);

/// A number as typed: the whole text a decimal number, finite, and neither overflowing nor
/// underflowing a double (1e-400 would read as 0); UsageError naming the option otherwise.
double parseNumber(const std::string& option, const std::string& text);

/// --formats LIST: which of `known` the comma-separated list names (empty items skipped), as a
/// flag per name of `known`; UsageError for a name not among them, or for none.
std::vector<bool> parseFormatList(const std::string& list, const std::vector<std::string>& known);
int parsePositiveInteger(const std::string& option, const std::string& text);
std::vector<double> parseNumbers(const std::string& option, const std::string& text,
                                 std::size_t count, char separator);
std::pair<int, int> parseSize(const std::string& option, const std::string& text);

/// A stored frame's id as typed on the command line, any positive bigint (the store's ids);
/// UsageError otherwise.
std::int64_t parseFrameId(const std::string& text);

/// The options that change the traced scene, and how the help describes them.
const std::vector<OptionSpec>& sceneOverrideSpecs();
extern const char* const kSceneOverrideHelp;
/// Applies the scene overrides given on the command line to the source.
void applySceneOverrides(const Options& options, vtkGeodesicSource* source);

/// The share of a frame's rays that may fail (numerically or on the step budget) before the
/// frame is refused: --max-failed-share (one of sceneOverrideSpecs), a fraction in [0, 1], else
/// kDefaultMaxFailedShare. Throws UsageError for any other value.
constexpr double kDefaultMaxFailedShare = 0.05;
double maxFailedShare(const Options& options);
/// After a trace: prints on stdout how the frame's rays ended ("LABEL: N rays, F failed
/// numerically, B out of steps"), then throws std::runtime_error (exit 1) if (F + B)/N exceeds
/// `maxShare`: such a frame is no picture of its scene, and must not be written or stored as one.
void checkRayEnds(vtkImageData* frame, double maxShare, const std::string& label);
/// As above, for a frame's records (one per pixel; those still Running were not traced), counted
/// as vtkGeodesicSource::CountRayEnds counts an image's.
void checkRayEnds(const std::vector<RayRecord>& frame, double maxShare, const std::string& label);

/// --db, --quiet
const std::vector<OptionSpec>& databaseSpecs();
extern const char* const kDatabaseHelp;
/// --db, else $ASRT_DB, else "" (what the user named, unresolved).
std::string databaseGiven(const Options& options);
/// The conninfo from --db, else $ASRT_DB, else the PG* variables, else the private embedded
/// server (started if needed). Throws DatabaseError.
std::string databaseConnection(const Options& options);

/// How long a read of the database waits for a table that another session holds locked:
/// $ASRT_LOCK_TIMEOUT seconds (0: as long as the lock is held), else the store's default (30 s).
/// Throws UsageError naming the variable for anything but a number of seconds from 0 to 2147483.
std::chrono::milliseconds readLockTimeout();
/// Puts the limits of the command line's reads on a store or a reader: readLockTimeout(), and
/// Ctrl-C or SIGTERM cancelling the statement under way, a wait for a lock included.
void limitReads(RayStore& store);
void limitReads(vtkGeodesicPostgreSQLReader* reader);

/// Concatenates option lists.
std::vector<OptionSpec> operator+(std::vector<OptionSpec> a, const std::vector<OptionSpec>& b);

/// Where a subcommand writes: --output as given, or, when it names a directory (an existing one
/// or one ending in '/') or is absent, that directory (default: the current one) joined with the
/// scene file's name without its extension and `suffix`. Creates missing parent directories.
std::string outputPath(const Options& options, const std::string& scenePath,
                       const std::string& suffix);
/// outputPath for a prefix of several files (PREFIX.png, PREFIX-000.vti, ...): throws UsageError
/// naming --output when the prefix itself is a device, a FIFO or a socket, which several files
/// cannot be written through one by one (-o /dev/null would otherwise make /dev/null.png).
std::string outputPrefix(const Options& options, const std::string& scenePath);
/// The frames of an earlier sequence at `prefix` beyond a new one of `count` frames: regular
/// files named PREFIX-NNN.png and PREFIX-NNN.vti (NNN the frame's number, "%03d"), numbered
/// `count` or more. Nothing else is ever taken. A new sequence removes them in the commit of its
/// set: they would look like part of it.
std::vector<std::string> staleFrames(const std::string& prefix, int count);

/// Scene files are read whole by the program itself, at most kMaxSceneBytes (SceneFile.h).
/// The scene file's text, read so that Ctrl-C or SIGTERM stops even a read that blocks (a FIFO).
/// Throws InputError if it cannot be read (missing, too large, not text), Interrupted on an
/// interrupt.
std::string readSceneFile(const std::string& path);
/// Gives the source the scene file at `path` as read by readSceneFile (its file name as well:
/// errors name it, textures are found beside it).
void setSceneFile(vtkGeodesicSource* source, const std::string& path);

/// Updates the source with a progress bar labelled `label` (none when `quiet`). Throws
/// InputError with the source's message if it failed (everything that fails in the source is the
/// scene or its parameters), Interrupted on Ctrl-C.
void traceFrame(vtkGeodesicSource* source, const std::string& label, bool quiet);

/// Text from a database or a file shown on a terminal: control characters escaped, so that a
/// hostile frame name cannot move the cursor or hide itself.
std::string printable(const std::string& text);

/// The directory of the scene presets (Data/scenes): $ASRT_DATA_DIR/scenes, else those installed
/// with this program, else those of the source tree it was built from.
std::string scenesDirectory();

/// MPI runs (asrt trace --mpi under mpirun): every process runs the same command; process 0
/// writes the files and speaks. Without MPI in this build, startParallelRun throws UsageError.
struct ParallelRun
{
  int rank = 0;
  int size = 1;
  /// The vtkMPIController, also VTK's global controller.
  vtkMultiProcessController* controller = nullptr;
};
/// Initializes MPI once and returns the run (also later calls); throws UsageError when this asrt
/// was built without MPI.
const ParallelRun& startParallelRun();
/// The active run, or null outside `--mpi`.
const ParallelRun* parallelRun();
/// Marks the failure being thrown as one every process reports together (the distributed
/// source agreed on it): the processes then end together instead of aborting the job.
void markSharedFailure();
/// Whether this process should stay silent about the failure it reports (a shared failure is
/// reported by process 0 alone).
bool silentParallelFailure();
/// Ends an MPI run, if any, with `code`: MPI_Finalize on success or after a shared failure;
/// otherwise the other processes may be waiting for this one, so MPI_Abort ends the whole job.
/// Returns `code`.
int finishParallelRun(int code);

// The subcommands: each parses its arguments and returns an exit code, or throws one of the
// errors above (or std::exception: a runtime failure).
int runTrace(const std::vector<std::string>& args);
int runList(const std::vector<std::string>& args);
int runShow(const std::vector<std::string>& args);
int runInterpolate(const std::vector<std::string>& args);
int runMovie(const std::vector<std::string>& args);
int runBundle(const std::vector<std::string>& args);
int runBench(const std::vector<std::string>& args);
int runDb(const std::vector<std::string>& args);
}
}

#endif
