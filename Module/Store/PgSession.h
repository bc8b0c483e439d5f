// libpq sessions as the store uses them: connections set up alike, statements whose failure
// throws StoreError with the server's message and SQLSTATE, typed binary parameters and results,
// transactions that roll back on any exception, binary COPY input, and the checks and quoting
// that text needs before it reaches SQL. Internal to ASRT::Store (EmbeddedPostgres and RayStore).
#ifndef asrt_PgSession_h
#define asrt_PgSession_h

#include "RayStore.h"

#include <libpq-fe.h>

#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace asrt
{
namespace pg
{
struct ResultDeleter
{
  void operator()(PGresult* r) const { PQclear(r); }
};
using Result = std::unique_ptr<PGresult, ResultDeleter>;

struct ConnectionDeleter
{
  void operator()(PGconn* c) const { PQfinish(c); }
};
using Connection = std::unique_ptr<PGconn, ConnectionDeleter>;

/// Writes begin READ COMMITTED whatever the server's default: the frame-identity checks rely on
/// its row locking, and COPY FREEZE refuses a transaction that holds a snapshot.
extern const char* const WriteBegin;
/// Reads see one snapshot and can change nothing.
extern const char* const ReadBegin;

/// A message of libpq's (PQerrorMessage, PQresultErrorMessage) as one line, as every message of
/// the store is: libpq spreads one error over several lines (the server's DETAIL and HINT, an
/// excerpt of the statement with a caret under the error, a CONTEXT, its own explanations indented
/// by a tab, a long sentence wrapped). The server's message and its DETAIL and HINT are kept,
/// joined by "; "; the statement excerpt, QUERY, CONTEXT and LOCATION are left out (the store's
/// SQL, not the user's); libpq's indented explanations join the line they explain, a wrapped
/// sentence its beginning.
std::string oneLine(const std::string& message);

/// A connection set up as every connection of the store is: a connect_timeout of 10 s unless the
/// conninfo or PGCONNECT_TIMEOUT sets one, UTF8, notices silenced. Throws StoreError with libpq's
/// reason ("cannot connect to PostgreSQL: ...").
Connection connect(const std::string& conninfo);
/// Reconnects a connection that broke (server restart, terminated backend); whether it is up.
bool reconnect(PGconn* conn);

/// The SQLSTATE of a statement that gave up waiting for a lock (lock_not_available: lock_timeout
/// ran out).
extern const char* const LockNotAvailableState;

/// The StoreError of a statement that gave up waiting for a lock: what it was doing ("listing the
/// frames failed") and the relation it waited for, as the statement names it, when the server
/// pointed at it (else empty: a row, or a lock other than a table's).
class LockNotAvailable : public StoreError
{
public:
  LockNotAvailable(std::string what, const std::string& message, std::string relation)
    : StoreError(message, LockNotAvailableState)
    , What(std::move(what))
    , Relation(std::move(relation))
  {
  }
  const std::string& doing() const { return this->What; }
  const std::string& relation() const { return this->Relation; }

private:
  std::string What;
  std::string Relation;
};

/// The relation named where the server's error `r` points in the statement `sql` (or in the
/// query of a function it ran); empty if it points nowhere.
std::string relationAtError(const PGresult* r, const std::string& sql);

/// Throws StoreError "<what>: <the server's message>", with its SQLSTATE; LockNotAvailable for a
/// statement `sql` (when given) that gave up waiting for a lock.
[[noreturn]] void fail(const std::string& what, PGconn* conn, const PGresult* r,
                       const std::string& sql = std::string());
/// Asks the server to cancel the statement under way on `conn` (best effort).
void cancelQuery(PGconn* conn);

/// Parameters for PQexecParams, all typed, doubles and integers in binary (exact).
class Params
{
public:
  Params& text(const std::string& s) { return this->add(s, 25, 0); }
  Params& bytes(const std::string& s) { return this->add(s, 17, 1); }
  Params& f64(double d);
  Params& i64(std::int64_t v) { return this->word(std::uint64_t(v), 8, 20); }
  Params& i32(std::int32_t v) { return this->word(std::uint32_t(v), 4, 23); }

  /// Runs one statement; its results in binary.
  Result exec(PGconn* conn, const std::string& sql, const std::string& what) const;

  /// Runs a query whose rows come one at a time (single-row mode: the client never holds more
  /// than one row), calling row(result) for each, binary.
  template<class Row>
  void stream(PGconn* conn, const std::string& sql, const std::string& what, Row row) const;

private:
  struct Arrays
  {
    explicit Arrays(const Params& p);
    std::vector<const char*> Values;
    std::vector<int> Lengths;
  };
  void sendStreamed(PGconn* conn, const std::string& sql, const std::string& what) const;
  Params& add(const std::string& s, Oid type, int format);
  Params& word(std::uint64_t w, int size, Oid type);
  std::vector<std::string> Values;
  std::vector<Oid> Types;
  std::vector<int> Formats;
};

/// Runs one statement without parameters.
Result exec(PGconn* conn, const std::string& sql, const std::string& what);
/// Runs a script of several statements (the migrations).
void execScript(PGconn* conn, const std::string& sql, const std::string& what);

// Readers of binary-format result values.
std::int64_t getI64(const PGresult* r, int row, int col);
std::int32_t getI32(const PGresult* r, int row, int col);
double getF64(const PGresult* r, int row, int col);
bool getBool(const PGresult* r, int row, int col);
std::string getText(const PGresult* r, int row, int col);

/// Refuses (StoreError) what PostgreSQL's text cannot hold exactly: invalid UTF-8 and NUL bytes.
/// `what` names the text in the message ("the label").
void requireText(const std::string& s, const char* what);
/// `name` quoted as an SQL identifier; throws StoreError "<what>: <libpq's reason>".
std::string quoteIdentifier(PGconn* conn, const std::string& name, const std::string& what);

/// Leaves an interrupted COPY and rolls the transaction back, if the connection is up. Never
/// throws.
void rollback(PGconn* conn) noexcept;

/// Runs `body` in a transaction begun with `begin`, rolling back if it throws. `body` commits or
/// rolls back itself.
template<typename F>
auto transaction(PGconn* conn, const char* begin, F&& body)
{
  exec(conn, begin, "starting a transaction failed");
  try
  {
    return body();
  }
  catch (...)
  {
    rollback(conn);
    throw;
  }
}

/// Binary COPY input, streamed to the server in ~1 MB messages.
class CopyWriter
{
public:
  CopyWriter(PGconn* conn, const std::string& copySql, const char* what);
  /// Starts a row of `fields` fields.
  void row(std::uint16_t fields);
  void i32(std::int32_t v);
  void i64(std::int64_t v);
  /// A bytea field of `size` bytes; returns where to write them.
  char* bytes(std::size_t size);
  void finish();

private:
  void u16(std::uint16_t v);
  void u32(std::uint32_t v);
  char* grow(std::size_t size);
  std::string failure() const;
  void send();
  static constexpr std::size_t Flush = 1 << 20;
  PGconn* Conn;
  const char* What;
  std::string Buf;
};

template<class Row>
void Params::stream(PGconn* conn, const std::string& sql, const std::string& what, Row row) const
{
  this->sendStreamed(conn, sql, what);
  // Every result is consumed, even after an error, so that the connection is ready again.
  std::string error, state, relation;
  while (PGresult* raw = PQgetResult(conn))
  {
    Result r(raw);
    const ExecStatusType st = PQresultStatus(raw);
    if (st == PGRES_SINGLE_TUPLE && error.empty())
    {
      try
      {
        row(raw);
      }
      catch (const StoreError& e)
      {
        // Stop asking for rows; the rest are read and dropped.
        error = e.what();
        state = e.sqlState();
        cancelQuery(conn);
      }
    }
    else if (st != PGRES_SINGLE_TUPLE && st != PGRES_TUPLES_OK && error.empty())
    {
      const char* s = PQresultErrorField(raw, PG_DIAG_SQLSTATE);
      error = what + ": " + oneLine(PQresultErrorMessage(raw));
      state = s ? s : "";
      relation = relationAtError(raw, sql);
    }
  }
  if (!error.empty() && state == LockNotAvailableState)
  {
    throw LockNotAvailable(what, error, relation);
  }
  if (!error.empty())
  {
    throw StoreError(error, state);
  }
  if (PQstatus(conn) != CONNECTION_OK)
  {
    fail(what, conn, nullptr);
  }
}
}
}

#endif
