#include "PgSession.h"

#include "StoreRecordCodec.h"

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <cstring>

namespace asrt
{
namespace pg
{
const char* const WriteBegin = "BEGIN ISOLATION LEVEL READ COMMITTED";
const char* const ReadBegin = "BEGIN ISOLATION LEVEL REPEATABLE READ READ ONLY";
const char* const LockNotAvailableState = "55P03";

namespace
{
bool lower(char c)
{
  return c >= 'a' && c <= 'z';
}

bool upper(char c)
{
  return c >= 'A' && c <= 'Z';
}

bool startsWith(const std::string& s, const char* prefix)
{
  return s.compare(0, std::strlen(prefix), prefix) == 0;
}

/// Whether `line` begins with a field label as libpq prints the server's fields: capitals, a colon
/// and two spaces ("ERROR:  ", "DETAIL:  ", "HINT:  ", "CONTEXT:  ").
bool labelled(const std::string& line)
{
  std::size_t k = 0;
  while (k < line.size() && upper(line[k]))
  {
    ++k;
  }
  return k > 0 && line.compare(k, 3, ":  ") == 0;
}

/// Lines that show the store's SQL or the server's source rather than what went wrong: the
/// statement excerpt ("LINE 1: SELECT ...", a caret line follows), QUERY, CONTEXT, LOCATION.
bool leftOut(const std::string& line)
{
  if (startsWith(line, "LINE "))
  {
    const std::size_t colon = line.find(':');
    return colon != std::string::npos && colon > 5 &&
           line.find_first_not_of("0123456789", 5) == colon;
  }
  return startsWith(line, "QUERY:  ") || startsWith(line, "CONTEXT:  ") ||
         startsWith(line, "LOCATION:  ") || startsWith(line, "STATEMENT:  ");
}
}

std::string oneLine(const std::string& message)
{
  std::vector<std::string> pieces;
  bool leavingOut = false; // inside a field that is left out (its further lines go with it)
  std::size_t at = 0;
  while (at < message.size())
  {
    std::size_t end = message.find('\n', at);
    end = end == std::string::npos ? message.size() : end;
    std::string line = message.substr(at, end - at);
    at = end + 1;
    const bool indented = !line.empty() && (line[0] == '\t' || line[0] == ' ');
    const std::size_t first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos)
    {
      continue;
    }
    line = line.substr(first, line.find_last_not_of(" \t\r") + 1 - first);
    if (!indented && leftOut(line))
    {
      leavingOut = true;
      continue;
    }
    if (!indented && labelled(line))
    {
      leavingOut = false;
    }
    else if (leavingOut)
    {
      continue;
    }
    else if (indented && !pieces.empty())
    {
      // libpq's own explanation of the line before ("\tIs the server running ..."), or the rest
      // of a sentence it wrapped ("\tbefore or while processing the request.").
      if (lower(line[0]))
      {
        pieces.back() += " " + line;
        continue;
      }
      // A sentence of its own after "; ", its capital lowered (not an acronym's: "SSL ...").
      if (upper(line[0]) && !(line.size() > 1 && upper(line[1])))
      {
        line[0] = char(line[0] - 'A' + 'a');
      }
    }
    pieces.push_back(line);
  }
  // libpq may say the same twice (a failed send, then the failed read of the same statement).
  std::vector<std::string> distinct;
  for (const std::string& piece : pieces)
  {
    if (std::find(distinct.begin(), distinct.end(), piece) == distinct.end())
    {
      distinct.push_back(piece);
    }
  }
  std::string out;
  for (std::size_t k = 0; k < distinct.size(); ++k)
  {
    std::string piece = distinct[k];
    if (k + 1 < distinct.size() && piece.size() > 1 && piece.back() == '.' &&
        piece[piece.size() - 2] != '.')
    {
      piece.pop_back(); // the sentence goes on after "; "
    }
    out += (k > 0 ? "; " : "") + piece;
  }
  return out;
}

Connection connect(const std::string& conninfo)
{
  // Keywords before "dbname" are overridden by what the expanded conninfo sets itself.
  std::vector<const char*> keys, values;
  if (!std::getenv("PGCONNECT_TIMEOUT"))
  {
    keys.push_back("connect_timeout");
    values.push_back("10");
  }
  keys.push_back("fallback_application_name");
  values.push_back("asrt");
  keys.push_back("dbname");
  values.push_back(conninfo.c_str());
  keys.push_back(nullptr);
  values.push_back(nullptr);
  Connection conn(PQconnectdbParams(keys.data(), values.data(), 1));
  if (!conn || PQstatus(conn.get()) != CONNECTION_OK)
  {
    throw StoreError("cannot connect to PostgreSQL: " +
                     (conn ? oneLine(PQerrorMessage(conn.get())) : "out of memory"));
  }
  if (PQsetClientEncoding(conn.get(), "UTF8") != 0)
  {
    throw StoreError("cannot set the client encoding to UTF8: " +
                     oneLine(PQerrorMessage(conn.get())));
  }
  // The server's notices ("table does not exist, skipping", ...) are not the caller's business;
  // libpq would print them on stderr.
  PQsetNoticeProcessor(
    conn.get(), [](void*, const char*) {}, nullptr);
  return conn;
}

bool reconnect(PGconn* conn)
{
  PQreset(conn);
  if (PQstatus(conn) != CONNECTION_OK)
  {
    return false;
  }
  PQsetClientEncoding(conn, "UTF8");
  return true;
}

std::string relationAtError(const PGresult* r, const std::string& sql)
{
  // A lock on a table is taken where the statement names it, and the server's error points there
  // (a character position, from 1; the store's SQL is ASCII).
  const char* position = nullptr;
  std::string text;
  if (r && (position = PQresultErrorField(r, PG_DIAG_STATEMENT_POSITION)))
  {
    text = sql;
  }
  else if (r && (position = PQresultErrorField(r, PG_DIAG_INTERNAL_POSITION)))
  {
    const char* query = PQresultErrorField(r, PG_DIAG_INTERNAL_QUERY);
    text = query ? query : "";
  }
  const long at = position ? std::strtol(position, nullptr, 10) - 1 : -1;
  if (at < 0 || std::size_t(at) >= text.size())
  {
    return std::string();
  }
  // An identifier, possibly qualified by its schema: letters, digits, '_', '$' and '.'.
  std::size_t end = std::size_t(at);
  while (end < text.size() && (std::isalnum(static_cast<unsigned char>(text[end])) ||
                               text[end] == '_' || text[end] == '$' || text[end] == '.'))
  {
    ++end;
  }
  return text.substr(std::size_t(at), end - std::size_t(at));
}

[[noreturn]] void fail(const std::string& what, PGconn* conn, const PGresult* r,
                       const std::string& sql)
{
  std::string msg = r ? PQresultErrorMessage(r) : "";
  if (msg.empty())
  {
    msg = PQerrorMessage(conn);
  }
  const char* state = r ? PQresultErrorField(r, PG_DIAG_SQLSTATE) : nullptr;
  if (state && std::strcmp(state, LockNotAvailableState) == 0)
  {
    throw LockNotAvailable(what, what + ": " + oneLine(msg), relationAtError(r, sql));
  }
  throw StoreError(what + ": " + oneLine(msg), state ? state : "");
}

void cancelQuery(PGconn* conn)
{
  if (PGcancel* c = PQgetCancel(conn))
  {
    char why[256];
    PQcancel(c, why, int(sizeof why));
    PQfreeCancel(c);
  }
}

// ---------------------------------------------------------------------------------------------
// Statements.

Params& Params::f64(double d)
{
  return this->word(storage::bitsOf(d), 8, 701);
}

Params::Arrays::Arrays(const Params& p)
{
  for (const std::string& v : p.Values)
  {
    this->Values.push_back(v.data());
    this->Lengths.push_back(int(v.size()));
  }
}

Result Params::exec(PGconn* conn, const std::string& sql, const std::string& what) const
{
  const Arrays a(*this);
  Result r(PQexecParams(conn, sql.c_str(), int(a.Values.size()), this->Types.data(),
                        a.Values.data(), a.Lengths.data(), this->Formats.data(), 1));
  const ExecStatusType st = r ? PQresultStatus(r.get()) : PGRES_FATAL_ERROR;
  if (st != PGRES_COMMAND_OK && st != PGRES_TUPLES_OK)
  {
    fail(what, conn, r.get(), sql);
  }
  return r;
}

void Params::sendStreamed(PGconn* conn, const std::string& sql, const std::string& what) const
{
  const Arrays a(*this);
  if (!PQsendQueryParams(conn, sql.c_str(), int(a.Values.size()), this->Types.data(),
                         a.Values.data(), a.Lengths.data(), this->Formats.data(), 1) ||
      !PQsetSingleRowMode(conn))
  {
    fail(what, conn, nullptr);
  }
}

Params& Params::add(const std::string& s, Oid type, int format)
{
  this->Values.push_back(s);
  this->Types.push_back(type);
  this->Formats.push_back(format);
  return *this;
}

Params& Params::word(std::uint64_t w, int size, Oid type)
{
  char b[8];
  for (int k = 0; k < size; ++k)
  {
    b[k] = char(w >> (8 * (size - 1 - k)));
  }
  return this->add(std::string(b, size), type, 1);
}

Result exec(PGconn* conn, const std::string& sql, const std::string& what)
{
  return Params().exec(conn, sql, what);
}

void execScript(PGconn* conn, const std::string& sql, const std::string& what)
{
  Result r(PQexec(conn, sql.c_str()));
  if (!r || PQresultStatus(r.get()) != PGRES_COMMAND_OK)
  {
    fail(what, conn, r.get(), sql);
  }
}

namespace
{
std::uint64_t readBE(const char* p, int size)
{
  std::uint64_t w = 0;
  for (int k = 0; k < size; ++k)
  {
    w = (w << 8) | std::uint8_t(p[k]);
  }
  return w;
}
}

std::int64_t getI64(const PGresult* r, int row, int col)
{
  return std::int64_t(readBE(PQgetvalue(r, row, col), 8));
}
std::int32_t getI32(const PGresult* r, int row, int col)
{
  return std::int32_t(readBE(PQgetvalue(r, row, col), 4));
}
double getF64(const PGresult* r, int row, int col)
{
  return storage::doubleOf(readBE(PQgetvalue(r, row, col), 8));
}
bool getBool(const PGresult* r, int row, int col)
{
  return PQgetvalue(r, row, col)[0] != 0;
}
std::string getText(const PGresult* r, int row, int col)
{
  return std::string(PQgetvalue(r, row, col), std::size_t(PQgetlength(r, row, col)));
}

// ---------------------------------------------------------------------------------------------
// Text.

void requireText(const std::string& s, const char* what)
{
  std::size_t k = 0;
  while (k < s.size())
  {
    const unsigned char c = static_cast<unsigned char>(s[k]);
    int len = c < 0x80 ? 1 : (c >> 5) == 6 ? 2 : (c >> 4) == 14 ? 3 : (c >> 3) == 30 ? 4 : 0;
    bool ok = len > 0 && c != 0 && k + len <= s.size() && c != 0xC0 && c != 0xC1 && c <= 0xF4;
    for (int m = 1; ok && m < len; ++m)
    {
      ok = (static_cast<unsigned char>(s[k + m]) & 0xC0) == 0x80;
    }
    if (ok && len > 1)
    {
      // Overlong forms, surrogates and code points above U+10FFFF.
      const unsigned char d = static_cast<unsigned char>(s[k + 1]);
      ok = !(c == 0xE0 && d < 0xA0) && !(c == 0xED && d >= 0xA0) && !(c == 0xF0 && d < 0x90) &&
           !(c == 0xF4 && d >= 0x90);
    }
    if (!ok)
    {
      throw StoreError(std::string(what) + " is not valid UTF-8 text (byte " + std::to_string(k) +
                       (c == 0 ? " is NUL" : " starts an invalid sequence") +
                       "); it was not stored");
    }
    k += len;
  }
}

std::string quoteIdentifier(PGconn* conn, const std::string& name, const std::string& what)
{
  char* quoted = PQescapeIdentifier(conn, name.c_str(), name.size());
  if (!quoted)
  {
    throw StoreError(what + ": " + oneLine(PQerrorMessage(conn)));
  }
  std::string s = quoted;
  PQfreemem(quoted);
  return s;
}

// ---------------------------------------------------------------------------------------------
// Transactions.

namespace
{
/// Leaves a COPY that an error interrupted, so that the connection can roll back.
void abandonCopy(PGconn* conn, const char* why)
{
  if (PQtransactionStatus(conn) != PQTRANS_ACTIVE)
  {
    return;
  }
  // The state of an interrupted COPY is only visible through the results still to come.
  PQputCopyEnd(conn, why);
  while (PGresult* r = PQgetResult(conn))
  {
    PQclear(r);
    if (PQstatus(conn) == CONNECTION_BAD)
    {
      break;
    }
  }
}
}

void rollback(PGconn* conn) noexcept
{
  if (PQstatus(conn) != CONNECTION_OK)
  {
    return;
  }
  abandonCopy(conn, "aborted by the client");
  if (PQtransactionStatus(conn) != PQTRANS_IDLE)
  {
    PQclear(PQexec(conn, "ROLLBACK"));
  }
}

// ---------------------------------------------------------------------------------------------
// Binary COPY.

CopyWriter::CopyWriter(PGconn* conn, const std::string& copySql, const char* what)
  : Conn(conn)
  , What(what)
{
  Result copy(PQexec(conn, copySql.c_str()));
  if (!copy || PQresultStatus(copy.get()) != PGRES_COPY_IN)
  {
    fail(std::string("starting to write ") + what + " failed", conn, copy.get());
  }
  this->Buf.reserve(Flush + (1 << 16));
  this->Buf.append("PGCOPY\n\377\r\n\0", 11);
  this->u32(0);
  this->u32(0);
}

void CopyWriter::row(std::uint16_t fields)
{
  if (this->Buf.size() >= Flush)
  {
    this->send();
  }
  this->u16(fields);
}

void CopyWriter::i32(std::int32_t v)
{
  this->u32(4);
  storage::putI32(this->grow(4), v);
}

void CopyWriter::i64(std::int64_t v)
{
  this->u32(8);
  storage::putI64(this->grow(8), v);
}

char* CopyWriter::bytes(std::size_t size)
{
  this->u32(std::uint32_t(size));
  return this->grow(size);
}

void CopyWriter::finish()
{
  this->u16(0xFFFF);
  this->send();
  if (PQputCopyEnd(this->Conn, nullptr) != 1)
  {
    fail(this->failure(), this->Conn, nullptr);
  }
  Result r(PQgetResult(this->Conn));
  if (!r || PQresultStatus(r.get()) != PGRES_COMMAND_OK)
  {
    fail(this->failure(), this->Conn, r.get());
  }
  while (PGresult* extra = PQgetResult(this->Conn))
  {
    PQclear(extra);
  }
}

void CopyWriter::u16(std::uint16_t v)
{
  const std::uint16_t w = __builtin_bswap16(v);
  std::memcpy(this->grow(2), &w, 2);
}

void CopyWriter::u32(std::uint32_t v)
{
  storage::putI32(this->grow(4), v);
}

char* CopyWriter::grow(std::size_t size)
{
  const std::size_t at = this->Buf.size();
  this->Buf.resize(at + size);
  return &this->Buf[at];
}

std::string CopyWriter::failure() const
{
  return std::string("writing ") + this->What + " failed";
}

void CopyWriter::send()
{
  if (!this->Buf.empty() && PQputCopyData(this->Conn, this->Buf.data(), int(this->Buf.size())) != 1)
  {
    fail(this->failure(), this->Conn, nullptr);
  }
  this->Buf.clear();
}
}
}
