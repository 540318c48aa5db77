#include <string>
#include <vector>

#include "io/mesh_buffer.hpp"
#include "io/readers.hpp"

namespace nonplanar::io {
namespace {

// Reads the next non-empty, non-comment line split into tokens.
bool next_record(Tokenizer& tok, std::vector<std::string_view>& out, int* line) {
  out.clear();
  while (!tok.at_end()) {
    std::string_view l = tok.rest_of_line();
    *line = tok.line();
    tok.skip_line();
    if (const auto hash = l.find('#'); hash != std::string_view::npos) l = l.substr(0, hash);
    Tokenizer words(l);
    for (std::string_view w = words.next(); !w.empty(); w = words.next()) out.push_back(w);
    if (!out.empty()) return true;
  }
  return false;
}

}  // namespace

Expected<TriangleMesh> parse_off(std::string_view data) {
  if (data.empty()) return Error{Status::parse_error, "file is empty"};
  Tokenizer tok(data);
  std::vector<std::string_view> rec;
  int line = 1;
  if (!next_record(tok, rec, &line)) return Error{Status::parse_error, "file has no content"};
  const std::string_view head = rec[0];
  if (head.size() < 3 || head.substr(head.size() - 3) != "OFF")
    return parse_error_at(line, "missing OFF header");
  if (head.find("4") != std::string_view::npos || head.find("n") != std::string_view::npos)
    return parse_error_at(line, "only 3D OFF is supported, not '" + std::string(head) + "'");
  rec.erase(rec.begin());  // counts may follow the header on the same line
  if (rec.empty() && !next_record(tok, rec, &line))
    return parse_error_at(line, "missing vertex and face counts");
  if (rec.size() < 2) return parse_error_at(line, "expected vertex and face counts");
  const auto nv = parse_int(rec[0]);
  const auto nf = parse_int(rec[1]);
  if (!nv || !nf || *nv < 0 || *nf < 0)
    return parse_error_at(line, "vertex and face counts must be non-negative integers");
  // Every record needs at least a few bytes; larger counts mean a truncated or lying header.
  if (*nv > static_cast<long long>(data.size()) / 2 ||
      *nf > static_cast<long long>(data.size()) / 2)
    return parse_error_at(line, "counts (" + std::to_string(*nv) + " vertices, " +
                                    std::to_string(*nf) + " faces) exceed what the file holds");
  if (*nf == 0) return Error{Status::invalid_mesh, "OFF file has no faces"};

  TriangleMesh mesh;
  mesh.vertices.reserve(static_cast<std::size_t>(*nv));
  for (long long i = 0; i < *nv; ++i) {
    if (!next_record(tok, rec, &line))
      return parse_error_at(line, "file ends after " + std::to_string(i) + " of " +
                                      std::to_string(*nv) + " vertices");
    if (rec.size() < 3) return parse_error_at(line, "vertex needs 3 coordinates");
    Vec3 v;
    for (int k = 0; k < 3; ++k) {
      const auto d = parse_double(rec[k]);
      if (!d)
        return parse_error_at(line, "vertex coordinate '" + std::string(rec[k].substr(0, 40)) +
                                        "' is not a finite number");
      v[k] = *d;
    }
    mesh.vertices.push_back(v);
  }
  for (long long i = 0; i < *nf; ++i) {
    if (!next_record(tok, rec, &line))
      return parse_error_at(
          line, "file ends after " + std::to_string(i) + " of " + std::to_string(*nf) + " faces");
    const auto n = parse_int(rec[0]);
    if (!n || *n < 3 || static_cast<std::size_t>(*n) + 1 > rec.size())
      return parse_error_at(line, "face needs a vertex count of at least 3 and that many indices");
    std::vector<int> poly;
    for (long long k = 1; k <= *n; ++k) {
      const auto idx = parse_int(rec[static_cast<std::size_t>(k)]);
      if (!idx || *idx < 0 || *idx >= *nv)
        return parse_error_at(line, "face index '" + std::string(rec[k].substr(0, 40)) +
                                        "' is out of range (" + std::to_string(*nv) + " vertices)");
      poly.push_back(static_cast<int>(*idx));
    }
    for (std::size_t k = 1; k + 1 < poly.size(); ++k)
      mesh.faces.push_back({poly[0], poly[k], poly[k + 1]});
  }
  return mesh;
}

}  // namespace nonplanar::io
