// The one G-code reader (program.hpp): every line classified, every move with what it carries,
// problems listed with their lines instead of failing, so each caller decides what it refuses
// (check: anything unreadable; the mapping of another slicer's file: anything inside the print).
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>
#include <limits>
#include <optional>
#include <string>

#include "core/huge_pages.hpp"
#include "core/text_tokens.hpp"
#include "nonplanar/program.hpp"

namespace nonplanar {

// A file's moves and lines are held whole (program.hpp): no padding back in between members.
static_assert(sizeof(void*) != 8 || (sizeof(GcodeMove) == 120 && sizeof(GcodeLine) == 40));
namespace {

// A bridge's or an overhang's ;HEIGHT: is its round bead's (the nozzle's diameter), not the
// thickness over anything under it: such moves keep the thickness in force before them.
bool bridged(std::string_view type) {
  for (std::string_view w : {"Bridge", "bridge", "Overhang", "overhang"})
    if (type.find(w) != std::string_view::npos) return true;
  return false;
}

using Kind = GcodeLine::Kind;

char upper(char c) {
  return static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
}

// A Klipper-style extended command: SET_PRINT_STATS_INFO, EXCLUDE_OBJECT_START, PRINT_START,
// or a lower-case name with an underscore (Klipper upper-cases commands itself). A word that
// is neither (random text) is not a command.
bool is_macro(std::string_view w) {
  if (w.size() < 2 || !std::isalpha(static_cast<unsigned char>(w[0]))) return false;
  // "G1X10" is a malformed G-code, not a macro's name.
  const char k = upper(w[0]);
  if ((k == 'G' || k == 'M') && std::isdigit(static_cast<unsigned char>(w[1]))) return false;
  bool upper_case = true, underscore = false;
  for (const char c : w) {
    const auto b = static_cast<unsigned char>(c);
    if (!std::isalnum(b) && c != '_') return false;
    if (std::islower(b)) upper_case = false;
    if (c == '_') underscore = true;
  }
  return upper_case || underscore;
}

// An M-code number: digits, optionally dotted (M862.3).
bool is_m_number(std::string_view n) {
  const std::size_t dot = n.find('.');
  auto digits = [](std::string_view s) {
    return !s.empty() && std::all_of(s.begin(), s.end(), [](char c) {
      return std::isdigit(static_cast<unsigned char>(c));
    });
  };
  return dot == std::string_view::npos ? digits(n)
                                       : digits(n.substr(0, dot)) && digits(n.substr(dot + 1));
}

// The line of text that starts at byte `at` (without its line end); `at` moves past it.
std::string_view next_line(std::string_view text, std::size_t& at) {
  std::size_t end = text.find('\n', at);
  if (end == std::string_view::npos) end = text.size();
  std::string_view l = text.substr(at, end - at);
  if (!l.empty() && l.back() == '\r') l.remove_suffix(1);
  at = end + 1;
  return l;
}

// Calls f(i, line) for each line of text (without its line end), i from 0.
template <class F>
void for_each_line(std::string_view text, F&& f) {
  std::size_t i = 0;
  for (std::size_t at = 0; at < text.size(); ++i) {
    const std::string_view l = next_line(text, at);
    f(i, l);
  }
}

// Reads a whole text into p, or, with a sink, hands every move to it and keeps no lines or
// moves (p then holds the problems and the per-file figures only); or, begun and then read
// to one line after another, a piece at a time (GcodePieceReader).
class Reader {
 public:
  using Sink = std::function<void(const GcodeMove&)>;
  using LineSink = std::function<void(const GcodeLine&, const GcodeMove*)>;
  Reader(GcodeProgram& p, const Sink* sink, const LineSink* lines = nullptr)
      : p_(p), sink_(sink), line_sink_(lines) {}
  void run(std::string_view text);
  /// Counts the lines (unless given) and finds the print; nothing is read yet.
  void begin(std::string_view text, std::optional<std::size_t> lines = std::nullopt);
  /// Reads on up to line `end` (0-based, not included).
  void read_to(std::size_t end);
  std::size_t lines() const { return n_; }
  std::size_t at_line() const { return i_; }
  std::size_t at_byte() const { return at_; }
  /// The ;TYPE: in force ("" before any), a view of the text.
  std::string_view type() const { return type_; }
  std::string_view text() const { return text_; }
  const GcodeState& state() const { return s_; }
  /// The ;LAYER_CHANGE lines of the print (each starts one of its layers).
  const std::vector<std::size_t>& layer_lines() const { return layer_lines_; }

 private:
  void comment(std::string_view c, std::size_t semi, GcodeLine& item, bool in_print);
  void command(std::string_view cmd, core::Tokenizer& tok, GcodeLine& item, std::size_t i);
  void set_position(core::Tokenizer& tok, GcodeLine& item);
  void move(core::Tokenizer& tok, GcodeLine& item, bool in_print);
  void problem(std::string why, bool moves_head = false) {
    p_.problems.push_back({line_, std::move(why), moves_head});
  }

  void find_print(std::string_view text);
  void read_line(std::size_t i, GcodeLine& item);

  GcodeProgram& p_;
  const Sink* sink_;
  const LineSink* line_sink_;
  GcodeMove last_;  // with line_sink_: the move of the line being read
  std::string_view text_;
  std::size_t n_ = 0;           // lines in the file
  std::size_t i_ = 0, at_ = 0;  // the next line to read, and its first byte
  std::vector<std::size_t> layer_lines_;
  int line_ = 0;
  Vec3 pos_{0, 0, 0};
  GcodeState s_;
  double width_ = 0.45, h_ = 0.2;
  double bead_h_ = 0.2;  // the latest ;HEIGHT: in force (a support layer's, the part's after it)
  // A bridge's or an overhang's thickness: bead_h_, but where the layer follows layers of
  // supports alone (PrusaSlicer's, between the part's), its height over the part's last layer,
  // not over the support's (its header's ;HEIGHT:): a layer whose first path was an overhang
  // was read 0.06 mm thick.
  double bridge_h_ = 0.2;
  double part_z_ = std::numeric_limits<double>::quiet_NaN();  // the last layer the part printed in
  bool layer_of_part_ = false, bridged_ = false, support_ = false;  // of the ;TYPE: in force
  bool wipe_ = false, layer_header_ = false;  // layer_header: ;LAYER_CHANGE seen, not ;HEIGHT:
  std::string_view type_;
  int layer_ = -1;
};

void Reader::run(std::string_view text) {
  const GcodeLineCount n = count_gcode_lines(text);
  // Reserved: grown by doubling, the bunny's 700 000 lines were copied over and over, and the
  // pages of each new block faulted in (a third of the reading). The moves get half as much
  // again for those the mapping's passes add (top skins' travels, pieces cut under a shell):
  // the first such move past the room doubled the vector, 82 MB more at the bunny's peak
  // through PrusaSlicer. Room never written is never resident.
  if (!sink_ && !line_sink_)
    reserve_huge(p_.lines, n.lines), reserve_huge(p_.moves, n.g_lines + n.g_lines / 2 + 1024);
  begin(text, n.lines);
  read_to(n_);
}

void Reader::begin(std::string_view text, std::optional<std::size_t> lines) {
  text_ = text;
  n_ = lines ? *lines : count_gcode_lines(text).lines;
  find_print(text);
}

void Reader::read_to(std::size_t end) {
  const bool keep = !sink_ && !line_sink_;
  for (; i_ < end && at_ < text_.size(); ++i_) {
    GcodeLine item;
    item.raw = next_line(text_, at_);
    read_line(i_, item);
    if (line_sink_) (*line_sink_)(item, item.kind == Kind::move ? &last_ : nullptr);
    if (keep) p_.lines.push_back(item);
  }
}

void Reader::find_print(std::string_view text) {
  std::size_t last_typed = 0, begin = std::string_view::npos;
  std::vector<std::size_t> custom;  // the ;TYPE:Custom lines
  for_each_line(text, [&](std::size_t i, std::string_view l) {
    if (l.rfind(";LAYER_CHANGE", 0) == 0) {
      if (begin == std::string_view::npos) begin = i;
      layer_lines_.push_back(i);
    }
    if (l.rfind(";TYPE:Custom", 0) == 0)
      custom.push_back(i);
    else if (l.rfind(";TYPE:", 0) == 0)
      last_typed = i;
  });
  p_.print_begin = p_.print_end = n_;
  if (begin == std::string_view::npos) return;
  p_.print_begin = begin;
  for (std::size_t i : custom)
    if (i >= std::max(last_typed, begin)) {
      p_.print_end = i;
      break;
    }
  std::erase_if(layer_lines_, [&](std::size_t i) { return i >= p_.print_end; });
}

void Reader::read_line(std::size_t i, GcodeLine& item) {
  line_ = static_cast<int>(i) + 1;
  const bool in_print = p_.in_print(i);
  if (i == p_.print_begin) p_.at_print = s_;
  if (i == p_.print_end) p_.at_end = s_;
  std::string_view l = item.raw;
  const std::size_t semi = l.find(';');
  if (semi != std::string_view::npos) {
    comment(l.substr(semi), semi, item, in_print);
    l = l.substr(0, semi);
  }
  item.layer = layer_;
  core::Tokenizer tok(l);
  const std::string_view cmd = tok.next();
  if (!cmd.empty()) command(cmd, tok, item, i);
  if (i + 1 == n_ && p_.print_end == n_) p_.at_end = s_;
}

void Reader::comment(std::string_view c, std::size_t semi, GcodeLine& item, bool in_print) {
  if (c.rfind(";TYPE:", 0) == 0) {
    type_ = c.substr(6);
    bridged_ = bridged(type_);
    support_ = role_from_name(type_) == ExtrusionRole::support;
  }
  if (c.rfind(";WIDTH:", 0) == 0)
    if (auto w = core::parse_double(c.substr(7)); w && *w > 0) width_ = *w;
  if (c.rfind(";WIPE_START", 0) == 0) wipe_ = true;
  if (c.rfind(";WIPE_END", 0) == 0) wipe_ = false;
  if (!in_print) return;
  if (c.rfind(";LAYER_CHANGE", 0) == 0) {
    if (layer_of_part_ && layer_ >= 0) part_z_ = p_.layer_z[static_cast<std::size_t>(layer_)];
    layer_of_part_ = false;
    ++layer_;
    p_.layer_height.push_back(h_);
    p_.layer_z.push_back(pos_.z() + h_);
    bead_h_ = bridge_h_ = h_;  // a layer without its own ;HEIGHT: keeps the last layer's
    layer_header_ = true;
  }
  // The layer's thickness is the ;HEIGHT: of its header; later ones are a bead's (a bridge's
  // is the nozzle's diameter) and pass untouched.
  if (layer_header_ && semi == 0 && c.rfind(";HEIGHT:", 0) == 0) {
    if (auto v = core::parse_double(c.substr(8)); v && *v > 0) h_ = *v, p_.layer_height.back() = h_;
    bead_h_ = bridge_h_ = h_;
    if (const double over_part = p_.layer_z.back() - part_z_; over_part > h_ + 1e-4)
      bridge_h_ = over_part;
    item.kind = Kind::height_comment;
    layer_header_ = false;
  } else if (semi == 0 && c.rfind(";HEIGHT:", 0) == 0 && !bridged_) {
    if (auto v = core::parse_double(c.substr(8)); v && *v > 0) bead_h_ = bridge_h_ = *v;
  }
  if (semi == 0 && c.rfind(";Z:", 0) == 0) {
    item.kind = Kind::z_comment;
    if (auto v = core::parse_double(c.substr(3)); v && layer_ >= 0)
      p_.layer_z[static_cast<std::size_t>(layer_)] = *v;
  }
}

void Reader::command(std::string_view cmd, core::Tokenizer& tok, GcodeLine& item, std::size_t i) {
  const char kind = upper(cmd[0]);
  if (kind == 'T') return;  // tool change: passes
  if (kind == 'M' && is_m_number(cmd.substr(1))) {
    const auto num = core::parse_int(cmd.substr(1));
    if (num && (*num == 82 || *num == 83)) {
      s_.relative_e = *num == 83;
      item.kind = Kind::e_mode, item.value = s_.relative_e;
    }
    if (num && (*num == 106 || *num == 107) && i < p_.print_begin) p_.fan_at_print = item.raw;
    return;
  }
  const auto num = kind == 'G' ? core::parse_int(cmd.substr(1)) : std::nullopt;
  if (!num) {
    if (!is_macro(cmd)) problem("'" + std::string(cmd.substr(0, 20)) + "' is not a G-code command");
    return;
  }
  switch (*num) {
    case 0:
    case 1:
      return move(tok, item, p_.in_print(i));
    case 92:
      return set_position(tok, item);
    case 90:
    case 91:
      s_.relative_xyz = *num == 91;
      if (s_.relative_xyz) item.kind = Kind::xyz_relative;
      return;
    case 2:
    case 3:
      return problem(
          "arc move (G2/G3): arcs cannot be measured or mapped onto curved layers; "
          "turn arc fitting off");
    case 20:
      return problem("inch units (G20) are not supported");
    case 28:
    case 29:
      return problem("'" + std::string(cmd) +
                         "' (home or probe) inside the print cannot be "
                         "mapped onto curved layers",
                     true);
    case 4:
    case 10:
    case 11:
    case 17:
    case 21:
    case 80:
    case 94:
      return;
    default:
      return problem("unknown G-code G" + std::to_string(*num));
  }
}

void Reader::set_position(core::Tokenizer& tok, GcodeLine& item) {
  for (std::string_view w = tok.next(); !w.empty(); w = tok.next()) {
    const auto v = core::parse_double(w.substr(1));
    if (!v) {
      problem("bad number in G92");
      continue;
    }
    const char a = upper(w[0]);
    if (a == 'E') s_.e = *v, item.kind = Kind::e_reset, item.value = *v;
    if (a == 'X') pos_.x() = *v;
    if (a == 'Y') pos_.y() = *v;
    if (a == 'Z') pos_.z() = *v;
  }
}

void Reader::move(core::Tokenizer& tok, GcodeLine& item, bool in_print) {
  GcodeMove m;
  m.line = line_, m.from = pos_, m.to = pos_;
  for (std::string_view w = tok.next(); !w.empty(); w = tok.next()) {
    const char a = upper(w[0]);
    const auto v = core::parse_double(w.substr(1));
    if (!v) {
      problem("bad number in '" + std::string(w.substr(0, 30)) + "'");
      continue;
    }
    const bool rel = s_.relative_xyz;
    if (a == 'X')
      m.to.x() = rel ? m.to.x() + *v : *v, m.has_xy = true;
    else if (a == 'Y')
      m.to.y() = rel ? m.to.y() + *v : *v, m.has_xy = true;
    else if (a == 'Z')
      m.to.z() = rel ? m.to.z() + *v : *v, m.has_z = true;
    else if (a == 'E')
      // G91 makes E relative too, as M83 does (Klipper, RepRapFirmware, Marlin 1 and
      // PrusaSlicer's viewer; read as absolute, a G91 retraction became 75x extrusion).
      m.has_e = true, m.de = s_.relative_e || rel ? *v : *v - s_.e,
      s_.e = s_.relative_e || rel ? s_.e + *v : *v;
    else if (a == 'F')
      m.f = *v;
    else
      problem("unknown word '" + std::string(w.substr(0, 20)) + "' in a move");
  }
  pos_ = m.to;
  if (!std::isnan(m.f)) s_.feed = m.f;
  m.feed = s_.feed;
  if (in_print && !m.has_xy && !m.has_z && m.has_e) {
    GcodeRetraction& r = p_.retraction;
    if (m.de < 0 && r.length == 0) r.length = -m.de, r.f = m.f;
    if (m.de > 0 && std::isnan(r.back_f)) r.back_f = m.f;
  }
  m.wipe = wipe_, m.type = type_, m.width = width_, m.layer = layer_;
  m.height = bridged_ ? bridge_h_ : bead_h_;
  if (!support_ && m.extruding()) layer_of_part_ = true;
  item.kind = Kind::move;
  if (sink_) return (*sink_)(m);
  if (line_sink_) return void(last_ = m);
  item.move = static_cast<int>(p_.moves.size());
  p_.moves.push_back(m);
}

}  // namespace

PrintMove print_move(const GcodeMove& g) {
  PrintMove m;
  m.from = g.from, m.to = g.to, m.filament = g.de, m.extruding = g.extruding(), m.wipe = g.wipe;
  m.type = g.type, m.layer = g.layer, m.width = g.width, m.line = g.line;
  return m;
}

GcodeProgram read_gcode_program(std::string_view text) {
  GcodeProgram p;
  Reader(p, nullptr).run(text);
  return p;
}

struct GcodePieceReader::Impl {
  explicit Impl(std::string_view text) : reader(p, nullptr) { reader.begin(text); }
  GcodeProgram p;
  Reader reader;
  Piece piece = Piece::start;
  bool started = false;
  std::size_t first = 0, next_layer = 0;
  std::size_t first_byte = 0;  // the piece's first line's
};

GcodePieceReader::GcodePieceReader(std::string_view text) : impl_(std::make_unique<Impl>(text)) {}
GcodePieceReader::~GcodePieceReader() = default;

bool GcodePieceReader::next(std::size_t layers) {
  Impl& m = *impl_;
  const std::vector<std::size_t>& at = m.reader.layer_lines();
  std::size_t to = m.reader.lines();
  if (!m.started) {
    m.started = true, to = m.p.print_begin;
  } else if (m.piece == Piece::start || (m.piece == Piece::layers && m.next_layer < at.size())) {
    if (m.next_layer == at.size()) {
      m.piece = Piece::end;  // no layers: the end follows the start
    } else {
      m.piece = Piece::layers;
      m.next_layer = std::min(at.size(), m.next_layer + std::max<std::size_t>(layers, 1));
      to = m.next_layer < at.size() ? at[m.next_layer] : m.p.print_end;
    }
  } else if (m.piece == Piece::layers) {
    m.piece = Piece::end;
  } else {
    return false;
  }
  m.p.lines.clear(), m.p.moves.clear(), m.p.problems.clear();
  m.first = m.reader.at_line(), m.first_byte = m.reader.at_byte();
  m.reader.read_to(to);
  if (m.piece == Piece::start && m.p.print_begin < m.reader.lines())
    m.p.at_print = m.reader.state();
  return true;
}

GcodePieceReader::Piece GcodePieceReader::piece() const {
  return impl_->piece;
}
std::size_t GcodePieceReader::first_line() const {
  return impl_->first;
}
std::size_t GcodePieceReader::layer_count() const {
  return impl_->reader.layer_lines().size();
}
std::size_t GcodePieceReader::held_from() const {
  const Impl& m = *impl_;
  const std::string_view type = m.reader.type();
  if (type.empty()) return m.first_byte;
  return std::min(m.first_byte, static_cast<std::size_t>(type.data() - m.reader.text().data()));
}
GcodeProgram& GcodePieceReader::program() {
  return impl_->p;
}

GcodeProgram for_each_gcode_line(std::string_view text,
                                 const std::function<void(const GcodeLine&, const GcodeMove*)>& f) {
  GcodeProgram p;
  Reader(p, nullptr, &f).run(text);
  return p;
}

std::vector<GcodeProblem> for_each_gcode_move(std::string_view text,
                                              const std::function<void(const GcodeMove&)>& f) {
  GcodeProgram p;
  Reader(p, &f).run(text);
  return std::move(p.problems);
}

GcodeLineCount count_gcode_lines(std::string_view text) {
  // As for_each_line splits: a last line without its line end counts, an empty end does not.
  // Line to line by memchr: a loop over every byte was two thirds of the reader's own time.
  GcodeLineCount n;
  for (std::size_t at = 0; at < text.size();) {
    ++n.lines, n.g_lines += (text[at] | 0x20) == 'g';
    const void* end = std::memchr(text.data() + at, '\n', text.size() - at);
    if (!end) break;
    at = static_cast<std::size_t>(static_cast<const char*>(end) - text.data()) + 1;
  }
  return n;
}

void for_each_print_move(std::string_view text, const std::function<bool(const GcodeMove&)>& keep,
                         const std::function<void(const PrintMove&)>& f) {
  for_each_gcode_move(text, [&](const GcodeMove& g) {
    if (!keep || keep(g)) f(print_move(g));
  });
}

Expected<std::vector<PrintMove>> read_gcode_moves(std::string_view text) {
  // Room for every G line: the vector never grows by copying, and the room no move takes is
  // never touched, so it costs address space, not memory.
  std::vector<PrintMove> moves;
  reserve_huge(moves, count_gcode_lines(text).g_lines);
  const auto problems =
      for_each_gcode_move(text, [&](const GcodeMove& g) { moves.push_back(print_move(g)); });
  for (const GcodeProblem& q : problems)
    if (!q.moves_head)
      return Error{Status::parse_error, "line " + std::to_string(q.line) + ": " + q.why};
  return moves;
}

std::optional<Error> first_unmappable(const GcodeProgram& p) {
  int line = 0;
  std::string why;
  for (const GcodeProblem& q : p.problems)
    if (p.in_print(static_cast<std::size_t>(q.line - 1))) {
      line = q.line, why = q.why;
      break;
    }
  for (const GcodeMove& m : p.moves) {
    if (line && m.line >= line) break;
    if (p.in_print(static_cast<std::size_t>(m.line - 1)) &&
        std::max(m.to.cwiseAbs().maxCoeff(), m.from.cwiseAbs().maxCoeff()) > 1e4) {
      line = m.line, why = "coordinate beyond 10 m: not a print this can map";
      break;
    }
  }
  if (!line) return std::nullopt;
  return Error{Status::parse_error, "line " + std::to_string(line) + ": " + why};
}

}  // namespace nonplanar
