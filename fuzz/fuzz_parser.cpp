// One libFuzzer target per parser: this file is compiled once per parser with
// NONPLANAR_FUZZ_PARSER set to its number (see fuzz/CMakeLists.txt). Every parser must return
// an Error for bad input; a crash, hang, leak or sanitizer report is a bug.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "io/readers.hpp"
#include "nonplanar/check.hpp"
#include "nonplanar/config.hpp"
#include "nonplanar/surface_io.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace nonplanar;
  const std::string_view in(reinterpret_cast<const char*>(data), size);
#if NONPLANAR_FUZZ_PARSER == 0
  MeshFormat f;
  (void)io::parse_stl(in, &f);
#elif NONPLANAR_FUZZ_PARSER == 1
  (void)io::parse_obj(in);
#elif NONPLANAR_FUZZ_PARSER == 2
  (void)io::parse_off(in);
#elif NONPLANAR_FUZZ_PARSER == 3
  (void)io::parse_3mf(in);
#elif NONPLANAR_FUZZ_PARSER == 4
  (void)parse_ini_config(in);
#elif NONPLANAR_FUZZ_PARSER == 5
  (void)parse_json_config(in);
#elif NONPLANAR_FUZZ_PARSER == 6
  (void)parse_surfaces_json(in);
#elif NONPLANAR_FUZZ_PARSER == 7
  (void)read_gcode_moves(in);
#else
#error "NONPLANAR_FUZZ_PARSER must name a parser (0-7)"
#endif
  return 0;
}
