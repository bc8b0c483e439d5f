#include "RayPredicate.h"

#include "RayStore.h"

#include <algorithm>
#include <cctype>
#include <cstring>

namespace asrt
{
namespace
{
enum class Kind
{
  Number,
  String,
  Keyword,
  Column,
  Function,
  Punctuation,
  End
};

struct Token
{
  Kind kind;
  std::string text; ///< as sent: keywords in upper case, names in lower case
  std::size_t at;   ///< 1-based byte position in the predicate
};

/// The keywords of the grammar (RayPredicate.h); every other keyword is refused.
const char* const Keywords[] = {
  "and", "or", "not", "is", "null", "true", "false", "between", "in"
};

/// Punctuation and operators, two-character ones first (a longer match wins).
const char* const Punctuation[] = { "<=", ">=", "<>", "!=", "(", ")", ",", "+",
                                    "-",  "*",  "/",  "%",  "^", "=", "<", ">" };

/// Values quoted in messages are cut to this many bytes.
constexpr std::size_t QuotedBytes = 40;

std::string quoted(const std::string& text)
{
  return "\"" + (text.size() > QuotedBytes ? text.substr(0, QuotedBytes) + "..." : text) + "\"";
}

[[noreturn]] void refuse(const std::string& what, std::size_t at, const std::string& why)
{
  throw StoreError("the ray predicate was refused: " + what + " at character " +
                   std::to_string(at) + (why.empty() ? "" : ": " + why));
}

std::string functionNames()
{
  std::string names;
  for (const RayPredicateFunction& f : rayPredicateFunctions())
  {
    names += (names.empty() ? "" : ", ") + std::string(f.name);
  }
  return names;
}

/// Why the character at `k`, which starts no token of the grammar, is refused.
[[noreturn]] void refuseCharacter(const std::string& p, std::size_t k)
{
  const char c = p[k];
  const std::string what = c == ':' && k + 1 < p.size() && p[k + 1] == ':'
                             ? std::string("a cast (::)")
                           : c == '"' ? std::string("a quoted identifier")
                                      : quoted(std::string(1, c));
  const std::string why = c == ';'    ? "a predicate is one expression, not statements"
                          : c == '$'  ? "no parameters or dollar quotes"
                          : c == '\\' ? "no backslashes"
                          : c == '.'  ? "no qualified names"
                          : c == '['  ? "no arrays"
                                      : "not an operator a predicate may use";
  refuse(what, k + 1, why);
}

/// PostgreSQL's numeric constant at `k`: digits, an optional decimal point and digits, an
/// optional exponent (an "e" without digits is left to be a name, as PostgreSQL does).
std::string lexNumber(const std::string& p, std::size_t& k)
{
  const std::size_t begin = k;
  auto digits = [&]
  {
    while (k < p.size() && std::isdigit(static_cast<unsigned char>(p[k])))
    {
      ++k;
    }
  };
  digits();
  if (k < p.size() && p[k] == '.')
  {
    ++k;
    digits();
  }
  if (k < p.size() && (p[k] == 'e' || p[k] == 'E'))
  {
    std::size_t e = k + 1;
    if (e < p.size() && (p[e] == '+' || p[e] == '-'))
    {
      ++e;
    }
    if (e < p.size() && std::isdigit(static_cast<unsigned char>(p[e])))
    {
      k = e;
      digits();
    }
  }
  return p.substr(begin, k - begin);
}

/// The string constant at `k`, '' standing for a quote inside it.
std::string lexString(const std::string& p, std::size_t& k)
{
  const std::size_t begin = k++;
  while (true)
  {
    if (k >= p.size())
    {
      refuse("an unterminated string", begin + 1, "");
    }
    if (p[k] == '\\')
    {
      // With standard_conforming_strings off a server would read it as an escape.
      refuse("a backslash", k + 1, "no backslashes, also not in strings");
    }
    if (p[k] == '\'')
    {
      if (k + 1 < p.size() && p[k + 1] == '\'')
      {
        k += 2;
        continue;
      }
      ++k;
      return p.substr(begin, k - begin);
    }
    ++k;
  }
}

/// The name at `k` as a keyword, a column or a function; any other name is refused.
Token lexName(const std::string& p, std::size_t& k)
{
  const std::size_t begin = k;
  while (k < p.size() &&
         (std::isalnum(static_cast<unsigned char>(p[k])) || p[k] == '_' || p[k] == '$'))
  {
    ++k;
  }
  std::string name = p.substr(begin, k - begin);
  std::transform(name.begin(), name.end(), name.begin(),
                 [](char c) { return char(std::tolower(static_cast<unsigned char>(c))); });
  for (const char* keyword : Keywords)
  {
    if (name == keyword)
    {
      std::string upper = name;
      std::transform(upper.begin(), upper.end(), upper.begin(),
                     [](char c) { return char(std::toupper(static_cast<unsigned char>(c))); });
      return { Kind::Keyword, upper, begin + 1 };
    }
  }
  const std::vector<std::string>& columns = rayPredicateColumns();
  if (std::find(columns.begin(), columns.end(), name) != columns.end())
  {
    return { Kind::Column, name, begin + 1 };
  }
  for (const RayPredicateFunction& f : rayPredicateFunctions())
  {
    if (name == f.name)
    {
      return { Kind::Function, name, begin + 1 };
    }
  }
  const std::size_t next = p.find_first_not_of(" \t\r\n", k);
  if (next != std::string::npos && p[next] == '(')
  {
    refuse(name + "()", begin + 1, "not a function a predicate may call (" + functionNames() + ")");
  }
  refuse(quoted(p.substr(begin, k - begin)), begin + 1,
         "neither a column of rays_v nor a keyword a predicate may use");
}

std::vector<Token> lex(const std::string& p)
{
  if (p.size() > kMaxRayPredicateBytes)
  {
    throw StoreError("the ray predicate was refused: it is longer than " +
                     std::to_string(kMaxRayPredicateBytes) + " bytes");
  }
  std::vector<Token> out;
  for (std::size_t k = 0; k < p.size();)
  {
    const unsigned char c = static_cast<unsigned char>(p[k]);
    if (c == ' ' || c == '\t' || c == '\n' || c == '\r')
    {
      ++k;
    }
    else if (c < 0x20 || c > 0x7E)
    {
      refuse("a character outside printable ASCII", k + 1, "");
    }
    else if (p.compare(k, 2, "--") == 0 || p.compare(k, 2, "/*") == 0)
    {
      refuse("a comment", k + 1, "");
    }
    else if (std::isdigit(c) ||
             (c == '.' && k + 1 < p.size() && std::isdigit(static_cast<unsigned char>(p[k + 1]))))
    {
      const std::size_t at = k + 1;
      out.push_back({ Kind::Number, lexNumber(p, k), at });
    }
    else if (std::isalpha(c) || c == '_')
    {
      out.push_back(lexName(p, k));
    }
    else if (c == '\'')
    {
      const std::size_t at = k + 1;
      out.push_back({ Kind::String, lexString(p, k), at });
    }
    else
    {
      const char* const* op =
        std::find_if(std::begin(Punctuation), std::end(Punctuation),
                     [&](const char* o) { return p.compare(k, std::strlen(o), o) == 0; });
      if (op == std::end(Punctuation))
      {
        refuseCharacter(p, k);
      }
      out.push_back({ Kind::Punctuation, *op, k + 1 });
      k += std::strlen(*op);
    }
  }
  out.push_back({ Kind::End, "", p.size() + 1 });
  return out;
}

/// A recursive-descent parser of the grammar in RayPredicate.h over the tokens of lex(); it
/// decides only whether the tokens form a predicate.
class Parser
{
public:
  explicit Parser(const std::vector<Token>& tokens)
    : Tokens(tokens)
  {
  }

  void predicate()
  {
    if (this->peek().kind == Kind::End)
    {
      throw StoreError("the ray predicate was refused: it is empty");
    }
    this->disjunction();
    if (this->peek().kind != Kind::End)
    {
      this->unexpected("AND, OR, an operator or the end");
    }
  }

private:
  /// One level of nesting, refused beyond kMaxRayPredicateDepth.
  struct Nesting
  {
    explicit Nesting(Parser& p)
      : P(p)
    {
      if (++this->P.Depth > kMaxRayPredicateDepth)
      {
        refuse("nesting deeper than " + std::to_string(kMaxRayPredicateDepth), p.peek().at, "");
      }
    }
    ~Nesting() { --this->P.Depth; }
    Parser& P;
  };

  const Token& peek() const { return this->Tokens[this->Pos]; }
  bool is(Kind kind, const char* text) const
  {
    return this->peek().kind == kind && this->peek().text == text;
  }
  bool accept(Kind kind, const char* text)
  {
    if (!this->is(kind, text))
    {
      return false;
    }
    ++this->Pos;
    return true;
  }
  void expect(Kind kind, const char* text)
  {
    if (!this->accept(kind, text))
    {
      this->unexpected(quoted(text));
    }
  }
  [[noreturn]] void unexpected(const std::string& expected) const
  {
    const Token& t = this->peek();
    refuse(t.kind == Kind::End ? std::string("the end") : quoted(t.text), t.at,
           "expected " + expected);
  }

  void disjunction()
  {
    const Nesting nesting(*this);
    this->conjunction();
    while (this->accept(Kind::Keyword, "OR"))
    {
      this->conjunction();
    }
  }
  void conjunction()
  {
    this->negation();
    while (this->accept(Kind::Keyword, "AND"))
    {
      this->negation();
    }
  }
  void negation()
  {
    if (this->accept(Kind::Keyword, "NOT"))
    {
      const Nesting nesting(*this);
      this->negation();
      return;
    }
    this->test();
  }
  void test()
  {
    this->sum();
    static const char* const comparisons[] = { "=", "<>", "!=", "<", "<=", ">", ">=" };
    for (const char* c : comparisons)
    {
      if (this->accept(Kind::Punctuation, c))
      {
        this->sum();
        return;
      }
    }
    if (this->accept(Kind::Keyword, "IS"))
    {
      this->accept(Kind::Keyword, "NOT");
      if (!this->accept(Kind::Keyword, "NULL") && !this->accept(Kind::Keyword, "TRUE") &&
          !this->accept(Kind::Keyword, "FALSE"))
      {
        this->unexpected("NULL, TRUE or FALSE");
      }
      return;
    }
    const bool negated = this->accept(Kind::Keyword, "NOT");
    if (this->accept(Kind::Keyword, "BETWEEN"))
    {
      this->sum();
      this->expect(Kind::Keyword, "AND");
      this->sum();
    }
    else if (this->accept(Kind::Keyword, "IN"))
    {
      this->list();
    }
    else if (negated)
    {
      this->unexpected("BETWEEN or IN");
    }
  }
  /// IN's list: literals only, so that no subquery and no other row can be named there.
  void list()
  {
    this->expect(Kind::Punctuation, "(");
    do
    {
      const bool signed_ =
        this->accept(Kind::Punctuation, "-") || this->accept(Kind::Punctuation, "+");
      const Kind k = this->peek().kind;
      const bool constant = this->is(Kind::Keyword, "TRUE") || this->is(Kind::Keyword, "FALSE") ||
                            this->is(Kind::Keyword, "NULL");
      if (k != Kind::Number && (signed_ || (k != Kind::String && !constant)))
      {
        this->unexpected(signed_ ? "a number" : "a number, a string, TRUE, FALSE or NULL");
      }
      ++this->Pos;
    } while (this->accept(Kind::Punctuation, ","));
    this->expect(Kind::Punctuation, ")");
  }
  void sum()
  {
    this->term();
    while (this->accept(Kind::Punctuation, "+") || this->accept(Kind::Punctuation, "-"))
    {
      this->term();
    }
  }
  void term()
  {
    this->factor();
    while (this->accept(Kind::Punctuation, "*") || this->accept(Kind::Punctuation, "/") ||
           this->accept(Kind::Punctuation, "%"))
    {
      this->factor();
    }
  }
  void factor()
  {
    this->unary();
    while (this->accept(Kind::Punctuation, "^"))
    {
      this->unary();
    }
  }
  void unary()
  {
    if (this->accept(Kind::Punctuation, "-") || this->accept(Kind::Punctuation, "+"))
    {
      const Nesting nesting(*this);
      this->unary();
      return;
    }
    this->primary();
  }
  void primary()
  {
    const Token& t = this->peek();
    const bool constant = this->is(Kind::Keyword, "TRUE") || this->is(Kind::Keyword, "FALSE") ||
                          this->is(Kind::Keyword, "NULL");
    if (t.kind == Kind::Number || t.kind == Kind::String || t.kind == Kind::Column || constant)
    {
      ++this->Pos;
    }
    else if (t.kind == Kind::Function)
    {
      this->call();
    }
    else if (this->accept(Kind::Punctuation, "("))
    {
      this->disjunction();
      this->expect(Kind::Punctuation, ")");
    }
    else
    {
      this->unexpected("a number, a string, a column, a function or \"(\"");
    }
  }
  void call()
  {
    const Token& name = this->peek();
    ++this->Pos;
    this->expect(Kind::Punctuation, "(");
    int arguments = 0;
    if (!this->accept(Kind::Punctuation, ")"))
    {
      do
      {
        this->disjunction();
        ++arguments;
      } while (this->accept(Kind::Punctuation, ","));
      this->expect(Kind::Punctuation, ")");
    }
    for (const RayPredicateFunction& f : rayPredicateFunctions())
    {
      if (name.text == f.name && (arguments < f.minArguments || arguments > f.maxArguments))
      {
        const std::string range =
          f.minArguments == f.maxArguments
            ? std::to_string(f.minArguments)
            : std::to_string(f.minArguments) + " to " + std::to_string(f.maxArguments);
        refuse(name.text + "()", name.at,
               "it takes " + range + " argument" + (f.maxArguments == 1 ? "" : "s") + ", not " +
                 std::to_string(arguments));
      }
    }
  }

  const std::vector<Token>& Tokens;
  std::size_t Pos = 0;
  int Depth = 0;
};
}

const std::vector<std::string>& rayPredicateColumns()
{
  static const std::vector<std::string> columns = { "frame_id",
                                                    "tile",
                                                    "block",
                                                    "ray",
                                                    "tile_ray",
                                                    "i",
                                                    "j",
                                                    "origin_x",
                                                    "origin_y",
                                                    "origin_z",
                                                    "dir_x",
                                                    "dir_y",
                                                    "dir_z",
                                                    "p_t",
                                                    "p_x",
                                                    "p_y",
                                                    "p_z",
                                                    "termination",
                                                    "object_id",
                                                    "hit_x",
                                                    "hit_y",
                                                    "hit_z",
                                                    "normal_x",
                                                    "normal_y",
                                                    "normal_z",
                                                    "u",
                                                    "v",
                                                    "chord_error",
                                                    "path_length",
                                                    "winding",
                                                    "image_order",
                                                    "steps",
                                                    "max_abs_h",
                                                    "color_r",
                                                    "color_g",
                                                    "color_b",
                                                    "rays_per_pixel",
                                                    "dudi",
                                                    "dudj",
                                                    "dvdi",
                                                    "dvdj",
                                                    "traced",
                                                    "record_bytes" };
  return columns;
}

const std::vector<RayPredicateFunction>& rayPredicateFunctions()
{
  // Each is pure arithmetic in pg_catalog for every argument type it takes: no catalog, no
  // setting, no state. GREATEST and LEAST take any number of arguments; 100 is plenty.
  static const std::vector<RayPredicateFunction> functions = {
    { "abs", 1, 1 },   { "acos", 1, 1 },       { "asin", 1, 1 },    { "atan", 1, 1 },
    { "atan2", 2, 2 }, { "cbrt", 1, 1 },       { "ceil", 1, 1 },    { "ceiling", 1, 1 },
    { "cos", 1, 1 },   { "cosh", 1, 1 },       { "degrees", 1, 1 }, { "exp", 1, 1 },
    { "floor", 1, 1 }, { "greatest", 1, 100 }, { "least", 1, 100 }, { "ln", 1, 1 },
    { "log", 1, 2 },   { "log10", 1, 1 },      { "mod", 2, 2 },     { "pi", 0, 0 },
    { "power", 2, 2 }, { "radians", 1, 1 },    { "round", 1, 2 },   { "sign", 1, 1 },
    { "sin", 1, 1 },   { "sinh", 1, 1 },       { "sqrt", 1, 1 },    { "tan", 1, 1 },
    { "tanh", 1, 1 },  { "trunc", 1, 2 }
  };
  return functions;
}

std::string rayPredicateSql(const std::string& predicate)
{
  const std::vector<Token> tokens = lex(predicate);
  Parser(tokens).predicate();
  std::string sql;
  for (const Token& t : tokens)
  {
    if (t.kind != Kind::End)
    {
      sql += (sql.empty() ? "" : " ") + t.text;
    }
  }
  return sql;
}
}
