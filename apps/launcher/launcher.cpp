// build/nonplanar: starts nonplanar-core, the program itself, from the same folder, with
// glibc's allocator backing its heap with transparent huge pages (GLIBC_TUNABLES=
// glibc.malloc.hugetlb=1). A page fault costs about 11 µs on the virtual machines measured
// here (64 MB touched page by page: 180 ms; as huge pages: 36-77 ms), and a slice writes
// tens of megabytes of fresh rasters, meshes and text: the sine roof sliced in 0.83 of the
// time, the wing and FoilCutter in 0.86, Benchy in 0.88. glibc reads the tunable only as a
// process starts, hence this launcher: static, so it costs 1-2 ms where the program's own
// start (34 shared libraries) costs 17. A GLIBC_TUNABLES the user set is left as it is;
// nonplanar-core takes ours out of its environment at once, so the slicers it runs get the user's.
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>

int main(int, char** argv) {
  char path[4096];
  constexpr char kCore[] = "nonplanar-core";
  const ssize_t n = readlink("/proc/self/exe", path, sizeof path - sizeof kCore);
  char* slash = nullptr;
  for (ssize_t i = 0; i < n; ++i)
    if (path[i] == '/') slash = path + i;
  if (!slash) {
    std::fprintf(stderr, "error: nonplanar: cannot find its own folder (/proc/self/exe)\n");
    return 1;
  }
  std::memcpy(slash + 1, kCore, sizeof kCore);
  if (!std::getenv("GLIBC_TUNABLES")) {
    setenv("GLIBC_TUNABLES", "glibc.malloc.hugetlb=1", 1);
    setenv("NONPLANAR_SET_TUNABLES", "1", 1);
  }
  execv(path, argv);
  std::fprintf(stderr, "error: %s: %s\n", path, std::strerror(errno));
  return 1;
}
