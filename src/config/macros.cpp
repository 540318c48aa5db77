// PrusaSlicer's placeholder language (macros.hpp): a recursive-descent evaluator over one
// block of text. Branches not taken are scanned, not evaluated, so a variable named only
// there is no error (PrusaSlicer's own printers use `{if has_wipe_tower}` that way).
#include "nonplanar/macros.hpp"

#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>

#include "config/macro_regex.hpp"
#include "core/text_tokens.hpp"

namespace nonplanar {
namespace {

using Type = MacroValue::Type;

struct Fail {
  std::string why;
};

bool numeric(const MacroValue& v) {
  return v.type == Type::integer || v.type == Type::real;
}
double as_real(const MacroValue& v) {
  return v.type == Type::real ? v.d : double(v.i);
}

std::string to_text(const MacroValue& v) {
  switch (v.type) {
    case Type::boolean:
      return v.b ? "true" : "false";
    case Type::integer:
      return std::to_string(v.i);
    case Type::real: {
      std::ostringstream ss;  // as PrusaSlicer: no trailing zeros, 6 significant digits
      ss << v.d;
      return ss.str();
    }
    case Type::text:
      return v.s;
  }
  return {};
}

bool truth(const MacroValue& v) {
  if (v.type == Type::boolean) return v.b;
  if (v.type == Type::integer) return v.i != 0;  // profiles store booleans as 0 / 1
  throw Fail{"a condition must be true or false"};
}

bool ident_start(char c) {
  return std::isalpha(static_cast<unsigned char>(c)) || c == '_';
}
bool ident_char(char c) {
  return std::isalnum(static_cast<unsigned char>(c)) || c == '_';
}

// One expression, from the text between { and }.
class Expression {
 public:
  /// `regex_budget`: NFA steps left to the =~ of the whole block (macro_regex.hpp).
  Expression(std::string_view s, const MacroVariables& vars, std::size_t& regex_budget)
      : s_(s), vars_(vars), regex_budget_(regex_budget) {}
  MacroValue parse_all() {
    MacroValue v = conditional();
    skip_space();
    if (p_ < s_.size()) throw Fail{"unexpected '" + std::string(s_.substr(p_)) + "'"};
    return v;
  }

 private:
  std::string_view s_;
  const MacroVariables& vars_;
  std::size_t p_ = 0;
  int depth_ = 0;  // nesting of (…), unary operators and ?: (each costs stack)
  std::size_t& regex_budget_;

  // Hostile input (#21): "((((…" or "- - - …" thousands deep would overflow the stack.
  struct Nest {
    explicit Nest(int& d) : d_(d) {
      if (++d_ > 400) throw Fail{"expression nested too deeply"};
    }
    ~Nest() { --d_; }
    int& d_;
  };

  void skip_space() {
    while (p_ < s_.size() && std::isspace(static_cast<unsigned char>(s_[p_]))) ++p_;
  }
  bool eat(std::string_view tok) {
    skip_space();
    if (s_.substr(p_, tok.size()) != tok) return false;
    // A word must end there ("or" is not the start of "order").
    if (ident_char(tok.back()) && p_ + tok.size() < s_.size() && ident_char(s_[p_ + tok.size()]))
      return false;
    p_ += tok.size();
    return true;
  }
  void expect(std::string_view tok) {
    if (!eat(tok)) throw Fail{"expected '" + std::string(tok) + "'"};
  }

  MacroValue conditional() {
    const Nest nest(depth_);
    MacroValue c = logical_or();
    if (!eat("?")) return c;
    MacroValue a = conditional();
    expect(":");
    MacroValue b = conditional();
    return truth(c) ? a : b;
  }
  MacroValue logical_or() {
    MacroValue a = logical_and();
    while (eat("or") || eat("||")) {
      const MacroValue b = logical_and();
      a = MacroValue::boolean(truth(a) || truth(b));
    }
    return a;
  }
  MacroValue logical_and() {
    MacroValue a = comparison();
    while (eat("and") || eat("&&")) {
      const MacroValue b = comparison();
      a = MacroValue::boolean(truth(a) && truth(b));
    }
    return a;
  }
  MacroValue comparison() {
    MacroValue a = additive();
    if (eat("=~")) return MacroValue::boolean(matches(a));
    if (eat("!~")) return MacroValue::boolean(!matches(a));
    for (const char* op : {"==", "!=", "<>", "<=", ">=", "<", ">"}) {
      if (!eat(op)) continue;
      const MacroValue b = additive();
      const std::string o = op;
      int cmp = 0;
      if (numeric(a) && numeric(b)) {
        const double x = as_real(a), y = as_real(b);
        cmp = x < y ? -1 : x > y ? 1 : 0;
      } else if (a.type == Type::text && b.type == Type::text) {
        cmp = a.s.compare(b.s);
      } else if (a.type == Type::boolean && b.type == Type::boolean && (o == "==" || o == "!=")) {
        cmp = a.b == b.b ? 0 : 1;
      } else {
        throw Fail{"cannot compare " + to_text(a) + " with " + to_text(b)};
      }
      bool r = o == "=="                ? cmp == 0
               : o == "!=" || o == "<>" ? cmp != 0
               : o == "<="              ? cmp <= 0
               : o == ">="              ? cmp >= 0
               : o == "<"               ? cmp < 0
                                        : cmp > 0;
      return MacroValue::boolean(r);
    }
    return a;
  }
  bool matches(const MacroValue& a) {
    skip_space();
    if (p_ >= s_.size() || s_[p_] != '/') throw Fail{"expected /regex/ after =~"};
    std::string re;
    for (++p_; p_ < s_.size() && s_[p_] != '/'; ++p_) {
      if (s_[p_] == '\\' && p_ + 1 < s_.size() && s_[p_ + 1] == '/') ++p_;
      re += s_[p_];
    }
    if (p_ >= s_.size()) throw Fail{"unterminated /regex/"};
    ++p_;
    if (a.type != Type::text) throw Fail{"=~ needs a string on its left"};
    const config::RegexResult r = config::regex_full_match(re, a.s, regex_budget_);
    if (!r.error.empty()) throw Fail{"/" + re.substr(0, 40) + "/: " + r.error};
    return r.matched;
  }
  MacroValue additive() {
    MacroValue a = multiplicative();
    for (;;) {
      if (eat("+")) {
        const MacroValue b = multiplicative();
        if (a.type == Type::text || b.type == Type::text)
          a = MacroValue::text(to_text(a) + to_text(b));
        else
          a = arithmetic(a, b, '+');
      } else if (eat("-")) {
        a = arithmetic(a, multiplicative(), '-');
      } else {
        return a;
      }
    }
  }
  MacroValue multiplicative() {
    MacroValue a = unary();
    for (;;) {
      if (eat("*"))
        a = arithmetic(a, unary(), '*');
      else if (eat("/"))
        a = arithmetic(a, unary(), '/');
      else if (eat("%"))
        a = arithmetic(a, unary(), '%');
      else
        return a;
    }
  }
  static MacroValue arithmetic(const MacroValue& a, const MacroValue& b, char op) {
    if (!numeric(a) || !numeric(b))
      throw Fail{std::string("'") + op + "' needs numbers, not " + to_text(a) + " and " +
                 to_text(b)};
    if ((op == '/' || op == '%') && as_real(b) == 0) throw Fail{"division by zero"};
    if (a.type == Type::integer && b.type == Type::integer)
      return MacroValue::integer(checked(a.i, b.i, op));
    const double x = as_real(a), y = as_real(b);
    switch (op) {
      case '+':
        return MacroValue::real(x + y);
      case '-':
        return MacroValue::real(x - y);
      case '*':
        return MacroValue::real(x * y);
      case '/':
        return MacroValue::real(x / y);
      default:
        return MacroValue::real(std::fmod(x, y));
    }
  }
  // Whole-number arithmetic without overflow (undefined in C++): an error instead.
  static long long checked(long long x, long long y, char op) {
    long long r = 0;
    bool over = false;
    switch (op) {
      case '+':
        over = __builtin_add_overflow(x, y, &r);
        break;
      case '-':
        over = __builtin_sub_overflow(x, y, &r);
        break;
      case '*':
        over = __builtin_mul_overflow(x, y, &r);
        break;
      default:  // '/' and '%'; y != 0 was checked
        over = x == std::numeric_limits<long long>::min() && y == -1;
        if (!over) r = op == '/' ? x / y : x % y;
    }
    if (over) throw Fail{"whole-number overflow"};
    return r;
  }
  static long long whole(double v, const std::string& fn) {
    if (!(std::abs(v) < 9e18))
      throw Fail{fn + "(): " + to_text(MacroValue::real(v)) + " is out of range"};
    return static_cast<long long>(v);
  }
  MacroValue unary() {
    const Nest nest(depth_);
    if (eat("-")) {
      MacroValue v = unary();
      if (v.type == Type::integer) return MacroValue::integer(checked(0, v.i, '-'));
      if (v.type == Type::real) return MacroValue::real(-v.d);
      throw Fail{"cannot negate " + to_text(v)};
    }
    if (eat("+")) return unary();
    if (eat("!") || eat("not")) return MacroValue::boolean(!truth(unary()));
    return primary();
  }
  MacroValue primary() {
    skip_space();
    if (p_ >= s_.size()) throw Fail{"expression ends early"};
    const char c = s_[p_];
    if (eat("(")) {
      MacroValue v = conditional();
      expect(")");
      return v;
    }
    if (c == '"') return string_literal();
    if (std::isdigit(static_cast<unsigned char>(c)) || c == '.') return number();
    if (!ident_start(c)) throw Fail{std::string("unexpected '") + c + "'"};
    const std::size_t a = p_;
    while (p_ < s_.size() && ident_char(s_[p_])) ++p_;
    const std::string name(s_.substr(a, p_ - a));
    if (name == "true" || name == "false") return MacroValue::boolean(name == "true");
    skip_space();
    if (p_ < s_.size() && s_[p_] == '(') return function(name);
    const std::vector<MacroValue>* var = vars_.find(name);
    if (!var) throw Fail{"'" + name + "' is not a variable"};
    long long index = 0;
    if (eat("[")) {
      const MacroValue i = conditional();
      expect("]");
      if (i.type != Type::integer) throw Fail{name + "[…]: the index must be a whole number"};
      index = i.i;
    }
    if (var->empty()) throw Fail{"'" + name + "' is empty"};
    if (index < 0 || index >= static_cast<long long>(var->size()))
      throw Fail{name + "[" + std::to_string(index) + "]: index out of range"};
    return (*var)[static_cast<std::size_t>(index)];
  }
  MacroValue string_literal() {
    std::string out;
    for (++p_; p_ < s_.size() && s_[p_] != '"'; ++p_) {
      if (s_[p_] == '\\' && p_ + 1 < s_.size()) ++p_;
      out += s_[p_];
    }
    if (p_ >= s_.size()) throw Fail{"unterminated string"};
    ++p_;
    return MacroValue::text(out);
  }
  MacroValue number() {
    const std::size_t a = p_;
    while (p_ < s_.size() && (std::isdigit(static_cast<unsigned char>(s_[p_])) || s_[p_] == '.'))
      ++p_;
    if (p_ < s_.size() && (s_[p_] == 'e' || s_[p_] == 'E')) {
      ++p_;
      if (p_ < s_.size() && (s_[p_] == '+' || s_[p_] == '-')) ++p_;
      while (p_ < s_.size() && std::isdigit(static_cast<unsigned char>(s_[p_]))) ++p_;
    }
    const std::string t(s_.substr(a, p_ - a));
    const auto d = core::parse_double(t);
    if (!d) throw Fail{"'" + t + "' is not a number"};
    if (t.find_first_of(".eE") == std::string::npos && std::abs(*d) < 9e18)
      return MacroValue::integer(static_cast<long long>(*d));
    return MacroValue::real(*d);
  }
  MacroValue function(const std::string& name) {
    expect("(");
    std::vector<MacroValue> args;
    if (!eat(")")) {
      do args.push_back(conditional());
      while (eat(","));
      expect(")");
    }
    auto need = [&](std::size_t lo, std::size_t hi) {
      if (args.size() < lo || args.size() > hi) throw Fail{name + "(): wrong number of arguments"};
      for (const MacroValue& a : args)
        if (!numeric(a)) throw Fail{name + "(): needs numbers, not " + to_text(a)};
    };
    if (name == "min" || name == "max") {
      need(2, 2);
      const bool lo = as_real(args[0]) < as_real(args[1]);
      return (name == "min") == lo ? args[0] : args[1];
    }
    if (name == "int") {
      need(1, 1);
      return MacroValue::integer(whole(as_real(args[0]), name));
    }
    if (name == "round") {
      need(1, 1);
      return MacroValue::integer(whole(std::round(as_real(args[0])), name));
    }
    if (name == "digits" || name == "zdigits") {
      need(2, 3);
      // Range-checked as doubles: a cast of 2e17 to int is undefined.
      const double w = as_real(args[1]), d = args.size() == 3 ? as_real(args[2]) : 0;
      if (!(w >= 0 && w <= 60 && d >= 0 && d <= 20)) throw Fail{name + "(): digits out of range"};
      const int width = static_cast<int>(w), decimals = static_cast<int>(d);
      char buf[128];
      std::snprintf(buf, sizeof buf, name == "zdigits" ? "%0*.*f" : "%*.*f", width, decimals,
                    as_real(args[0]));
      return MacroValue::text(buf);
    }
    throw Fail{"'" + name + "' is not a function"};
  }
};

// Legacy [name] or [name[index_name]]: the text of the variable, or nullopt when the brackets
// do not hold a name (then they are literal text, as in "M117 [ok]"… but an unknown name is
// an error, as in PrusaSlicer).
bool legacy(std::string_view inner, const MacroVariables& vars, std::string& out) {
  std::size_t p = 0;
  while (p < inner.size() && ident_char(inner[p])) ++p;
  if (p == 0 || !ident_start(inner[0])) return false;
  const std::string name(inner.substr(0, p));
  long long index = 0;
  if (p < inner.size()) {
    if (inner[p] != '[' || inner.back() != ']') return false;
    const std::string_view idx = inner.substr(p + 1, inner.size() - p - 2);
    for (char c : idx)
      if (!ident_char(c)) return false;
    const std::vector<MacroValue>* iv = vars.find(idx);
    if (!iv || iv->empty() || (*iv)[0].type != Type::integer)
      throw Fail{"'" + std::string(idx) + "' is not a whole-number variable"};
    index = (*iv)[0].i;
  }
  const std::vector<MacroValue>* var = vars.find(name);
  if (!var) throw Fail{"'" + name + "' is not a variable"};
  if (var->empty()) return out.clear(), true;
  if (index < 0 || index >= static_cast<long long>(var->size()))
    throw Fail{name + "[" + std::to_string(index) + "]: index out of range"};
  const MacroValue& v = (*var)[static_cast<std::size_t>(index)];
  if (v.type == Type::real) {
    char buf[40];  // as PrusaSlicer serialises a float option: up to 15 digits
    std::snprintf(buf, sizeof buf, "%.15g", v.d);
    out = buf;
  } else {
    out = to_text(v);
  }
  return true;
}

// One level of {if}: is the parent printing, has a branch been taken, is this one printing.
struct Branch {
  bool parent, taken, active;
  int line;  ///< of the {if}, for an {if} never closed
};

}  // namespace

void MacroVariables::set_from_profile(const std::string& key, const std::string& raw) {
  std::vector<MacroValue> values;
  if (!raw.empty() && raw.front() == '"') {  // "a";"b": one string per extruder
    for (std::string& item : core::ini_string_list(raw))
      values.push_back(MacroValue::text(std::move(item)));
    vars_[key] = std::move(values);
    return;
  }
  // Numbers, one or one per extruder: "0.4" or "215,215" (a percentage keeps its number).
  std::stringstream ss(raw);
  std::string item;
  bool all_numbers = !raw.empty() && key.find("gcode") == std::string::npos;
  while (all_numbers && std::getline(ss, item, ',')) {
    std::string t = item;
    t.erase(0, t.find_first_not_of(" \t"));
    t.erase(t.find_last_not_of(" \t\r") + 1);
    if (!t.empty() && t.back() == '%') t.pop_back();
    const auto d = core::parse_double(t);
    if (!d || t.empty()) {
      all_numbers = false;
      break;
    }
    values.push_back(t.find_first_of(".eE") == std::string::npos && std::abs(*d) < 9e18
                         ? MacroValue::integer(static_cast<long long>(*d))
                         : MacroValue::real(*d));
  }
  if (!all_numbers) values = {MacroValue::text(core::unescape_ini(raw))};
  vars_[key] = std::move(values);
}

const std::vector<MacroValue>* MacroVariables::find(std::string_view name) const {
  const auto it = vars_.find(name);
  return it == vars_.end() ? nullptr : &it->second;
}

Expected<std::string> expand_macros(std::string_view text, const MacroVariables& vars,
                                    const std::string& block) {
  std::string out;
  std::vector<Branch> branches;
  auto printing = [&] { return branches.empty() || branches.back().active; };
  int line = 1;
  // Where the last '[' found its ']' or line end: every '[' before it finds the same one, so a
  // line of "[[[[…" is read once, not once per bracket (found by fuzz_macros).
  std::size_t stop = 0;
  bool have_stop = false;
  // NFA steps for every =~ of the block: ample for any profile (a stock test costs a few
  // hundred), and a bound on what a hostile one can cost.
  std::size_t regex_budget = 5'000'000;
  try {
    for (std::size_t p = 0; p < text.size();) {
      const char c = text[p];
      if (c == '\n') ++line;
      if (c == '[') {
        if (!have_stop || p >= stop) stop = text.find_first_of("]\n", p + 1), have_stop = true;
        const std::size_t e = stop;
        // [a[b]]: the inner ] closes the index, the next one the expansion.
        std::size_t close = e;
        if (e != std::string_view::npos && text[e] == ']' && text.find('[', p + 1) < e)
          close = e + 1 < text.size() && text[e + 1] == ']' ? e + 1 : std::string_view::npos;
        std::string value;
        if (close != std::string_view::npos && text[close] == ']' && printing() &&
            legacy(text.substr(p + 1, close - p - 1), vars, value)) {
          out += value;
          p = close + 1;
          continue;
        }
      }
      if (c != '{') {
        if (printing()) out += c;
        ++p;
        continue;
      }
      const std::size_t e = text.find('}', p);
      if (e == std::string_view::npos) throw Fail{"'{' is never closed"};
      std::string_view inner = text.substr(p + 1, e - p - 1);
      for (char ch : inner) line += ch == '\n';
      p = e + 1;
      while (!inner.empty() && std::isspace(static_cast<unsigned char>(inner.front())))
        inner.remove_prefix(1);
      while (!inner.empty() && std::isspace(static_cast<unsigned char>(inner.back())))
        inner.remove_suffix(1);
      auto word = [&](std::string_view w) {
        return inner.substr(0, w.size()) == w &&
               (inner.size() == w.size() || !ident_char(inner[w.size()]));
      };
      auto cond = [&](std::size_t skip) {
        return truth(Expression(inner.substr(skip), vars, regex_budget).parse_all());
      };
      if (word("if")) {
        const bool parent = printing();
        const bool on = parent && cond(2);
        branches.push_back({parent, on, on, line});
      } else if (word("elsif")) {
        if (branches.empty()) throw Fail{"{elsif} without {if}"};
        Branch& b = branches.back();
        b.active = b.parent && !b.taken && cond(5);
        b.taken = b.taken || b.active;
      } else if (word("else")) {
        if (branches.empty()) throw Fail{"{else} without {if}"};
        Branch& b = branches.back();
        b.active = b.parent && !b.taken;
        b.taken = true;
      } else if (word("endif")) {
        if (branches.empty()) throw Fail{"{endif} without {if}"};
        branches.pop_back();
      } else if (printing()) {
        out += to_text(Expression(inner, vars, regex_budget).parse_all());
      }
    }
    if (!branches.empty()) {
      line = branches.back().line;
      throw Fail{"{if} without {endif}"};
    }
  } catch (const Fail& f) {
    return Error{Status::invalid_argument, block + ": line " + std::to_string(line) + ": " + f.why};
  }
  return out;
}

}  // namespace nonplanar
