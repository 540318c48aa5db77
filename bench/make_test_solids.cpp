// make_test_solids DIR: write the end-to-end and coverage issues' analytic solids
// (tests/support/solids.hpp) as binary STL, for scripts that slice them with nonplanar and
// PrusaSlicer.
#include <cstdio>
#include <filesystem>
#include <utility>

#include "nonplanar/io.hpp"
#include "support/solids.hpp"

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: make_test_solids DIR\n");
    return 2;
  }
  const std::filesystem::path dir = argv[1];
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  namespace t = nonplanar::test;
  const std::pair<const char*, nonplanar::TriangleMesh> solids[] = {
      {"saddle.stl", t::saddle()},
      {"sine_roof.stl", t::sine_roof()},
      {"domed_towers.stl", t::domed_towers()},
      {"dome_cut_by_box.stl", t::dome_cut_by_box()},
      {"rib.stl", t::rib()},
      {"rib_beside_tower.stl", t::rib_beside_tower()},
      {"hollow_roof_1.5mm.stl", t::hollow_roof(1.5)},
      {"hollow_roof_0.8mm.stl", t::hollow_roof(0.8)},
      {"two_reliefs.stl", t::two_reliefs()},
      {"rib_and_domed_tower.stl", t::rib_and_domed_tower()},
      {"mouse_shell.stl", t::mouse_shell()},
      {"top_over_pocket.stl", t::top_over_pocket()},
      {"tops_one_over_another.stl", t::tops_one_over_another()},
      {"filleted_block.stl", t::filleted_block()},
      {"terrain_tile.stl", t::terrain_tile()}};
  for (const auto& [name, mesh] : solids) {
    auto w = nonplanar::write_stl(dir / name, mesh);
    if (!w) {
      std::fprintf(stderr, "error: %s: %s\n", (dir / name).c_str(), w.error().message.c_str());
      return 1;
    }
  }
  return 0;
}
