// A regex is parsed into a tree, the tree compiled into a program of NFA instructions, and
// the program run over the text with every live state at once, so each character costs at
// most one step per instruction and nothing recurses on the text.
// Notation: pc: an instruction's index; Split x y: go on at both x and y (no character).
#include "config/macro_regex.hpp"

#include <bitset>
#include <cctype>
#include <vector>

namespace nonplanar::config {
namespace {

constexpr int kMaxDepth = 100;              // groups inside groups
constexpr int kMaxCount = 100;              // n of {m,n}
constexpr std::size_t kMaxProgram = 20000;  // instructions, after {m,n} copies

using CharSet = std::bitset<256>;

struct Fail {
  std::string why;
};

struct Node {
  enum Kind { set, cat, alt, repeat, begin, end } kind;
  CharSet chars;          // set
  std::vector<int> kids;  // cat, alt; repeat: one
  int min = 0, max = 0;   // repeat; max < 0: no limit
};

CharSet class_escape(char e) {
  CharSet s;
  for (int c = 0; c < 256; ++c) {
    const bool d = std::isdigit(c) != 0, w = std::isalnum(c) != 0 || c == '_',
               sp = c == ' ' || (c >= '\t' && c <= '\r');
    const char l = static_cast<char>(std::tolower(static_cast<unsigned char>(e)));
    const bool in = l == 'd' ? d : l == 'w' ? w : sp;
    s[static_cast<std::size_t>(c)] = std::isupper(static_cast<unsigned char>(e)) ? !in : in;
  }
  return s;
}

bool is_class_escape(char e) {
  return e == 'd' || e == 'D' || e == 'w' || e == 'W' || e == 's' || e == 'S';
}

class Parser {
 public:
  explicit Parser(std::string_view re) : re_(re) {}
  std::vector<Node> nodes;

  int parse() {
    const int root = alternation(0);
    if (p_ < re_.size()) throw Fail{"unmatched ')'"};
    return root;
  }

 private:
  int add(Node n) {
    nodes.push_back(std::move(n));
    return static_cast<int>(nodes.size()) - 1;
  }
  bool more() const { return p_ < re_.size(); }
  char peek() const { return re_[p_]; }

  int alternation(int depth) {
    if (depth > kMaxDepth) throw Fail{"groups nested too deeply"};
    Node a{Node::alt, {}, {}, 0, 0};
    a.kids.push_back(sequence(depth));
    while (more() && peek() == '|') ++p_, a.kids.push_back(sequence(depth));
    return a.kids.size() == 1 ? a.kids[0] : add(std::move(a));
  }
  int sequence(int depth) {
    Node c{Node::cat, {}, {}, 0, 0};
    while (more() && peek() != '|' && peek() != ')') c.kids.push_back(repeated(depth));
    return add(std::move(c));
  }
  int repeated(int depth) {
    int kid = atom(depth);
    if (!more()) return kid;
    int lo = 0, hi = -1;
    if (peek() == '*')
      ++p_;
    else if (peek() == '+')
      ++p_, lo = 1;
    else if (peek() == '?')
      ++p_, hi = 1;
    else if (!counts(lo, hi))
      return kid;
    if (more() && peek() == '?') ++p_;  // lazy: the same whole-string answer
    if (more() && (peek() == '*' || peek() == '+' || peek() == '?'))
      throw Fail{"nothing to repeat"};
    return add(Node{Node::repeat, {}, {kid}, lo, hi});
  }
  // `{m}`, `{m,}` or `{m,n}` at p_: consumed and true; anything else is a literal '{'.
  bool counts(int& lo, int& hi) {
    if (peek() != '{') return false;
    std::size_t q = p_ + 1;
    auto number = [&](int& out) {
      const std::size_t a = q;
      long v = 0;
      while (q < re_.size() && std::isdigit(static_cast<unsigned char>(re_[q])) && v <= kMaxCount)
        v = v * 10 + (re_[q++] - '0');
      out = static_cast<int>(v);
      return q > a;
    };
    if (!number(lo)) return false;
    hi = lo;
    if (q < re_.size() && re_[q] == ',') {
      ++q;
      if (!number(hi)) hi = -1;
    }
    if (q >= re_.size() || re_[q] != '}') return false;
    if (lo > kMaxCount || hi > kMaxCount) throw Fail{"a count over 100 in {m,n}"};
    if (hi >= 0 && hi < lo) throw Fail{"{m,n} with n < m"};
    p_ = q + 1;
    return true;
  }
  int atom(int depth) {
    const char c = re_[p_++];
    Node n{Node::set, {}, {}, 0, 0};
    switch (c) {
      case '(': {
        if (more() && peek() == '?') {
          if (p_ + 1 >= re_.size() || re_[p_ + 1] != ':')
            throw Fail{"lookarounds and named groups are not supported"};
          p_ += 2;
        }
        const int inner = alternation(depth + 1);
        if (!more() || peek() != ')') throw Fail{"missing ')'"};
        ++p_;
        return inner;
      }
      case '[':
        n.chars = bracket();
        return add(std::move(n));
      case '.':
        n.chars.set();
        n.chars['\n'] = n.chars['\r'] = false;
        return add(std::move(n));
      case '^':
        return add(Node{Node::begin, {}, {}, 0, 0});
      case '$':
        return add(Node{Node::end, {}, {}, 0, 0});
      case '*':
      case '+':
      case '?':
        throw Fail{"nothing to repeat"};
      case '\\':
        n.chars = escape(false);
        return add(std::move(n));
      default:
        n.chars[static_cast<unsigned char>(c)] = true;
        return add(std::move(n));
    }
  }
  // After a backslash: a class (\d …), a control character, or escaped punctuation.
  CharSet escape(bool in_class) {
    if (!more()) throw Fail{"a trailing backslash"};
    const char e = re_[p_++];
    CharSet s;
    if (is_class_escape(e)) return class_escape(e);
    const char controls[][2] = {{'n', '\n'}, {'t', '\t'}, {'r', '\r'}, {'f', '\f'}, {'v', '\v'}};
    for (const auto& [k, v] : controls)
      if (e == k) return s.set(static_cast<unsigned char>(v));
    if (in_class && e == 'b') return s.set('\b');
    if (std::isalnum(static_cast<unsigned char>(e)))
      throw Fail{std::string("\\") + e + " is not supported"};
    return s.set(static_cast<unsigned char>(e));
  }
  CharSet bracket() {
    CharSet s;
    const bool negate = more() && peek() == '^';
    if (negate) ++p_;
    while (more() && peek() != ']') {
      CharSet one;
      int lo = static_cast<unsigned char>(re_[p_++]);
      if (lo == '\\') {
        one = escape(true);
        if (one.count() != 1) {  // \d and friends cannot bound a range
          s |= one;
          continue;
        }
        for (int k = 0; k < 256; ++k)
          if (one[static_cast<std::size_t>(k)]) lo = k;
      }
      int hi = lo;
      if (p_ + 1 < re_.size() && peek() == '-' && re_[p_ + 1] != ']') {
        ++p_;
        hi = static_cast<unsigned char>(re_[p_++]);
        if (hi == '\\') {
          const CharSet h = escape(true);
          if (h.count() != 1) throw Fail{"a class escape ends a range"};
          for (int k = 0; k < 256; ++k)
            if (h[static_cast<std::size_t>(k)]) hi = k;
        }
        if (hi < lo) throw Fail{"a range out of order in [...]"};
      }
      for (int k = lo; k <= hi; ++k) s[static_cast<std::size_t>(k)] = true;
    }
    if (!more()) throw Fail{"missing ']'"};
    ++p_;
    return negate ? ~s : s;
  }

  std::string_view re_;
  std::size_t p_ = 0;
};

struct Inst {
  enum Op { set, split, jump, begin, end, match } op;
  int x = 0, y = 0;  // split: both; jump: x
  int chars = -1;    // set: index into Program::sets
};

struct Program {
  std::vector<Inst> code;
  std::vector<CharSet> sets;
};

class Compiler {
 public:
  Compiler(const std::vector<Node>& nodes, Program& p) : nodes_(nodes), p_(p) {}
  void emit(int id) {
    const Node& n = nodes_[static_cast<std::size_t>(id)];
    switch (n.kind) {
      case Node::set:
        p_.sets.push_back(n.chars);
        push({Inst::set, 0, 0, static_cast<int>(p_.sets.size()) - 1});
        return;
      case Node::begin:
      case Node::end:
        push({n.kind == Node::begin ? Inst::begin : Inst::end, 0, 0, -1});
        return;
      case Node::cat:
        for (int k : n.kids) emit(k);
        return;
      case Node::alt:
        return alternatives(n);
      case Node::repeat:
        return repeat(n);
    }
  }

 private:
  int here() const { return static_cast<int>(p_.code.size()); }
  int push(Inst i) {
    if (p_.code.size() >= kMaxProgram) throw Fail{"/regex/ too large once its counts are expanded"};
    p_.code.push_back(i);
    return here() - 1;
  }
  Inst& at(int pc) { return p_.code[static_cast<std::size_t>(pc)]; }
  void alternatives(const Node& n) {
    std::vector<int> jumps;
    for (std::size_t k = 0; k + 1 < n.kids.size(); ++k) {
      const int split = push({Inst::split, here() + 1, 0, -1});
      emit(n.kids[k]);
      jumps.push_back(push({Inst::jump, 0, 0, -1}));
      at(split).y = here();
    }
    emit(n.kids.back());
    for (int j : jumps) at(j).x = here();
  }
  void repeat(const Node& n) {
    for (int k = 0; k < n.min; ++k) emit(n.kids[0]);
    if (n.max < 0) {  // L: split body, out; body; jump L
      const int loop = push({Inst::split, here() + 1, 0, -1});
      emit(n.kids[0]);
      push({Inst::jump, loop, 0, -1});
      at(loop).y = here();
      return;
    }
    std::vector<int> splits;  // each optional copy may stop the run: all leave to the end
    for (int k = n.min; k < n.max; ++k) {
      splits.push_back(push({Inst::split, here() + 1, 0, -1}));
      emit(n.kids[0]);
    }
    for (int s : splits) at(s).y = here();
  }
  const std::vector<Node>& nodes_;
  Program& p_;
};

// Every state reached from `start` without reading a character, added to `list`. The states
// of one step share a generation in `mark`, so a state is added once per step and a loop of
// empty steps (`(a*)*`) ends.
class Runner {
 public:
  Runner(const Program& p, std::size_t n, std::size_t& budget)
      : p_(p), n_(n), budget_(budget), mark_(p.code.size(), 0) {}
  void begin_step() { ++generation_; }
  void close(std::vector<int>& list, int start, std::size_t pos) {
    stack_.assign(1, start);
    while (!stack_.empty()) {
      const int pc = stack_.back();
      stack_.pop_back();
      if (mark_[static_cast<std::size_t>(pc)] == generation_) continue;
      mark_[static_cast<std::size_t>(pc)] = generation_;
      if (budget_ == 0) throw Fail{"=~: /regex/ too costly for its text"};
      --budget_;
      const Inst& i = p_.code[static_cast<std::size_t>(pc)];
      if (i.op == Inst::jump) {
        stack_.push_back(i.x);
      } else if (i.op == Inst::split) {
        stack_.push_back(i.y), stack_.push_back(i.x);
      } else if (i.op == Inst::begin || i.op == Inst::end) {
        if (pos == (i.op == Inst::begin ? 0 : n_)) stack_.push_back(pc + 1);
      } else {
        list.push_back(pc);
      }
    }
  }

 private:
  const Program& p_;
  std::size_t n_;
  std::size_t& budget_;
  std::vector<std::size_t> mark_;
  std::vector<int> stack_;
  std::size_t generation_ = 0;
};

bool run(const Program& p, std::string_view text, std::size_t& budget) {
  Runner r(p, text.size(), budget);
  std::vector<int> now, next;
  r.begin_step();
  r.close(now, 0, 0);
  for (std::size_t pos = 0; pos < text.size() && !now.empty(); ++pos) {
    const auto c = static_cast<unsigned char>(text[pos]);
    next.clear();
    r.begin_step();
    for (int pc : now) {
      const Inst& i = p.code[static_cast<std::size_t>(pc)];
      if (i.op == Inst::set && p.sets[static_cast<std::size_t>(i.chars)][c])
        r.close(next, pc + 1, pos + 1);
    }
    now.swap(next);
  }
  for (int pc : now)
    if (p.code[static_cast<std::size_t>(pc)].op == Inst::match) return true;
  return false;
}

}  // namespace

RegexResult regex_full_match(std::string_view re, std::string_view text, std::size_t& budget) {
  try {
    Parser parser(re);
    const int root = parser.parse();
    Program program;
    Compiler(parser.nodes, program).emit(root);
    program.code.push_back({Inst::match, 0, 0, -1});
    return {run(program, text, budget), {}};
  } catch (const Fail& f) {
    return {false, f.why};
  }
}

}  // namespace nonplanar::config
