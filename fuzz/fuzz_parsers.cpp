// libFuzzer target for every text/binary parser: the first byte picks the parser, the rest
// is its input. Build: bash fuzz/run.sh (clang-14, ASan + UBSan); any crash, leak or UB
// report is a bug. Parsers must return an Error for bad input, never crash or hang.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "io/readers.hpp"
#include "nonplanar/check.hpp"
#include "nonplanar/config.hpp"
#include "nonplanar/surface_io.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const std::string_view in(reinterpret_cast<const char*>(data + 1), size - 1);
  using namespace nonplanar;
  switch (data[0] % 7) {
    case 0: {
      MeshFormat f;
      (void)io::parse_stl(in, &f);
      break;
    }
    case 1:
      (void)io::parse_obj(in);
      break;
    case 2:
      (void)io::parse_off(in);
      break;
    case 3:
      (void)parse_ini_config(in);
      break;
    case 4:
      (void)parse_json_config(in);
      break;
    case 5:
      (void)parse_surfaces_json(in);
      break;
    case 6:
      (void)read_gcode_moves(in);
      break;
  }
  return 0;
}
