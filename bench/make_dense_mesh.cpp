// make_dense_mesh OUT.stl [LEVELS]: write the benchmark's subdivided mesh for scripts.
#include <cstdio>
#include <string>

#include "dense_mesh.hpp"

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: make_dense_mesh OUT.stl [LEVELS=5]\n");
    return 2;
  }
  const std::string err =
      nonplanar::bench::write_dense_mesh(argv[1], argc > 2 ? std::stoi(argv[2]) : 5);
  if (!err.empty()) {
    std::fprintf(stderr, "error: %s\n", err.c_str());
    return 1;
  }
  return 0;
}
