#include "support/solids.hpp"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <utility>
#include <vector>

namespace nonplanar::test {

TriangleMesh height_field_solid(const std::function<double(double, double)>& f, double x0,
                                double x1, double y0, double y1, int nx, int ny, double base) {
  TriangleMesh m;
  const int cols = nx + 1, rows = ny + 1;
  auto top = [&](int i, int j) { return j * cols + i; };
  auto bot = [&](int i, int j) { return cols * rows + j * cols + i; };
  for (int layer = 0; layer < 2; ++layer)
    for (int j = 0; j < rows; ++j)
      for (int i = 0; i < cols; ++i) {
        const double x = x0 + (x1 - x0) * i / nx, y = y0 + (y1 - y0) * j / ny;
        m.vertices.emplace_back(x, y, layer == 0 ? f(x, y) : base);
      }
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      // Top: counter-clockwise seen from above; bottom: the reverse.
      m.faces.push_back({top(i, j), top(i + 1, j), top(i + 1, j + 1)});
      m.faces.push_back({top(i, j), top(i + 1, j + 1), top(i, j + 1)});
      m.faces.push_back({bot(i, j), bot(i + 1, j + 1), bot(i + 1, j)});
      m.faces.push_back({bot(i, j), bot(i, j + 1), bot(i + 1, j + 1)});
    }
  auto wall = [&](int a_top, int b_top, int a_bot, int b_bot) {  // a→b runs counter-clockwise
    m.faces.push_back({a_bot, b_bot, b_top});
    m.faces.push_back({a_bot, b_top, a_top});
  };
  for (int i = 0; i < nx; ++i) {
    wall(top(i, 0), top(i + 1, 0), bot(i, 0), bot(i + 1, 0));      // y = y0 side
    wall(top(i + 1, ny), top(i, ny), bot(i + 1, ny), bot(i, ny));  // y = y1 side
  }
  for (int j = 0; j < ny; ++j) {
    wall(top(nx, j), top(nx, j + 1), bot(nx, j), bot(nx, j + 1));  // x = x1 side
    wall(top(0, j + 1), top(0, j), bot(0, j + 1), bot(0, j));      // x = x0 side
  }
  return m;
}

TriangleMesh placed(TriangleMesh m, const PrintConfig& c) {
  const BoundingBox b = bounding_box(m);
  const Vec3 shift(c.bed_center().x() - 0.5 * (b.min.x() + b.max.x()),
                   c.bed_center().y() - 0.5 * (b.min.y() + b.max.y()), -b.min.z());
  for (Vec3& v : m.vertices) v += shift;
  return m;
}

TriangleMesh box(const Vec3& lo, const Vec3& hi) {
  return height_field_solid([&](double, double) { return hi.z(); }, lo.x(), hi.x(), lo.y(), hi.y(),
                            1, 1, lo.z());
}

TriangleMesh subdivide(const TriangleMesh& in, int levels) {
  TriangleMesh m = in;
  for (int l = 0; l < levels; ++l) {
    TriangleMesh next;
    next.vertices = m.vertices;
    std::map<std::pair<int, int>, int> mid;
    auto midpoint = [&](int a, int b) {
      const auto key = std::minmax(a, b);
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      next.vertices.push_back(0.5 * (m.vertices[a] + m.vertices[b]));
      const int id = static_cast<int>(next.vertices.size()) - 1;
      mid.emplace(key, id);
      return id;
    };
    for (const auto& f : m.faces) {
      const int ab = midpoint(f[0], f[1]), bc = midpoint(f[1], f[2]), ca = midpoint(f[2], f[0]);
      next.faces.push_back({f[0], ab, ca});
      next.faces.push_back({ab, f[1], bc});
      next.faces.push_back({ca, bc, f[2]});
      next.faces.push_back({ab, bc, ca});
    }
    m = std::move(next);
  }
  return m;
}

TriangleMesh icosphere(const Vec3& c, double r, int levels) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  TriangleMesh m;
  m.vertices = {{-1, t, 0},  {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t},  {0, 1, t},
                {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
  m.faces = {{0, 11, 5},  {0, 5, 1},  {0, 1, 7},  {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
             {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
             {3, 8, 9},   {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  m = subdivide(m, levels);
  for (Vec3& v : m.vertices) v = c + r * v.normalized();
  return m;
}

void append(TriangleMesh& a, const TriangleMesh& b) {
  const int base = static_cast<int>(a.vertices.size());
  a.vertices.insert(a.vertices.end(), b.vertices.begin(), b.vertices.end());
  for (auto f : b.faces) a.faces.push_back({f[0] + base, f[1] + base, f[2] + base});
}

std::filesystem::path shared_models() {
  const std::filesystem::path p = NONPLANAR_SHARED_MODELS;
  return std::filesystem::is_directory(p) ? p : std::filesystem::path();
}

std::filesystem::path temp_dir(const std::string& name) {
  // Unique per process and call: ctest runs tests in parallel processes. Removed when the
  // process ends: a run of the suite left some 60 folders in /tmp, and after a few hundred
  // runs the 20 000 entries there made every atomic write in /tmp (which looks for stale
  // temporaries of its own) take 18 ms.
  struct Made {
    std::vector<std::filesystem::path> dirs;
    ~Made() {
      std::error_code ec;
      for (const auto& d : dirs) std::filesystem::remove_all(d, ec);
    }
  };
  static Made made;
  static int counter = 0;
  const auto p = std::filesystem::temp_directory_path() /
                 ("nonplanar_test_" + name + "_" + std::to_string(::getpid()) + "_" +
                  std::to_string(counter++));
  std::filesystem::remove_all(p);
  std::filesystem::create_directories(p);
  made.dirs.push_back(p);
  return p;
}

TriangleMesh saddle() {
  return height_field_solid([](double x, double y) { return 10 + (x * x - y * y) / 60.0; }, -12, 12,
                            -12, 12, 72, 72);
}

TriangleMesh sine_roof(int nx, int ny) {
  return height_field_solid([](double x, double) { return 8 + std::sin(2 * M_PI * x / 25); }, 0, 50,
                            0, 30, nx, ny);
}

TriangleMesh domed_towers() {
  auto top = [](double x, double y) {
    for (double cx : {20.0, 60.0})
      if (std::abs(x - cx) <= 10 && std::abs(y - 20) <= 10)
        return 18 + 2.0 * std::cos(0.1 * (x - cx)) * std::cos(0.1 * (y - 20));
    return 3.0;
  };
  return height_field_solid(top, 0, 80, 0, 40, 160, 80);
}

TriangleMesh dome_cut_by_box() {
  const double R = 40, a = 12;
  return height_field_solid(
      [&](double x, double y) {
        return 6 + std::sqrt(R * R - x * x - y * y) - std::sqrt(R * R - 2 * a * a);
      },
      -a, a, -a, a, 72, 72);
}

TriangleMesh rib() {
  return height_field_solid([](double x, double) { return 0.3 + 12 * std::sin(M_PI * x / 100); }, 0,
                            80, 0, 12, 160, 12);
}

TriangleMesh rib_beside_tower() {
  TriangleMesh m = rib();
  append(m, box({82, 4, 0}, {86, 8, 14}));
  return m;
}

TriangleMesh rib_against_tower() {
  TriangleMesh m = rib();
  append(m, box({30, 12, 0}, {40, 16, 14}));
  return m;
}

TriangleMesh rib_and_domed_tower() {
  TriangleMesh m = height_field_solid(
      [](double x, double) { return 0.3 + 12 * std::sin(M_PI * x / 100); }, 0, 60, 0, 12, 120, 12);
  append(m, height_field_solid(
                [](double x, double y) {
                  return 18 + 2 * std::cos(0.1 * (x - 95)) * std::cos(0.1 * (y - 6));
                },
                80, 110, -9, 21, 60, 60));
  return m;
}

TriangleMesh rib_and_small_domed_tower() {
  TriangleMesh m = rib();
  append(m, height_field_solid(
                [](double x, double y) {
                  return 18 + 2 * std::cos(0.1 * (x - 95)) * std::cos(0.1 * (y - 6));
                },
                87.5, 102.5, -1.5, 13.5, 30, 30));
  return m;
}

TriangleMesh two_reliefs() {
  auto top = [](double x, double y) {
    if (x < 25) return 4 + 3 * std::sin(2 * M_PI * x / 25) * std::cos(y / 8);
    if (x < 45) return 2.0;
    return 10 + 3 * std::cos(2 * M_PI * (x - 45) / 25) * std::cos(y / 8);
  };
  return height_field_solid(top, 0, 70, 0, 30, 280, 60);
}

namespace {

// A closed void: the solid's faces turned inside out.
TriangleMesh inside_out(TriangleMesh m) {
  for (auto& f : m.faces) std::swap(f[1], f[2]);
  return m;
}

}  // namespace

TriangleMesh mouse_shell() {
  const double wall = 1.2;
  auto top = [](double x, double y) {
    const double u = (x - 4) / 26, v = y / 18;
    return 3 + 7 * (1 - u * u) * (1 - v * v);
  };
  TriangleMesh m = height_field_solid(top, -22, 22, -13, 13, 88, 52);
  append(m, inside_out(height_field_solid([&](double x, double y) { return top(x, y) - wall; },
                                          -22 + wall, 22 - wall, -13 + wall, 13 - wall, 84, 48,
                                          wall)));
  return m;
}

TriangleMesh top_over_pocket() {
  TriangleMesh m = height_field_solid(
      [](double x, double y) { return 8 + 1.5 * std::sin(x / 6) * std::cos(y / 8); }, 0, 40, 0, 30,
      80, 60);
  append(m, inside_out(box({10, 8, 1.5}, {30, 22, 5})));
  return m;
}

TriangleMesh tops_one_over_another() {
  TriangleMesh m =
      height_field_solid([](double x, double y) { return 5 + std::cos(x / 7) * std::cos(y / 6); },
                         0, 40, 0, 30, 80, 60);
  append(m, box({40, 5, 0}, {50, 25, 11}));
  append(m, height_field_solid(
                [](double x, double y) {
                  return 13 + std::cos((x - 40) / 6) * std::cos((y - 15) / 6);
                },
                30, 50, 5, 25, 40, 40, 10));
  return m;
}

TriangleMesh filleted_block() {
  const double r = 5, x1 = 40, y1 = 30, h = 12;
  auto top = [&](double x, double y) {
    const double a = std::max(0.0, r - std::min(x, x1 - x)),
                 b = std::max(0.0, r - std::min(y, y1 - y));
    return h - r + std::sqrt(std::max(0.0, r * r - a * a - b * b));
  };
  return height_field_solid(top, 0, x1, 0, y1, 160, 120);
}

TriangleMesh terrain_tile() {
  auto top = [](double x, double y) {
    return 6 + 1.8 * std::sin(x / 7 + 0.3) * std::cos(y / 9 + 1.1) +
           0.8 * std::sin(x / 3.7 + 2) * std::sin(y / 4.3 + 0.5) +
           0.3 * std::cos(x / 2.1 + 1) * std::sin(y / 1.9 + 2.2);
  };
  return height_field_solid(top, 0, 50, 0, 50, 100, 100);
}

TriangleMesh hollow_roof(double wall) {
  auto roof = [](double x, double y) { return 6 + 2.5 * std::sin(x / 7) * std::cos(y / 9); };
  TriangleMesh m = height_field_solid(roof, 0, 40, 0, 40, 80, 80);
  const int n = static_cast<int>(std::lround((40 - 2 * wall) / 0.5));
  TriangleMesh hole = height_field_solid([&](double x, double y) { return roof(x, y) - wall; },
                                         wall, 40 - wall, wall, 40 - wall, n, n, wall);
  for (auto& f : hole.faces) std::swap(f[1], f[2]);  // a void: inside out
  append(m, hole);
  return m;
}

}  // namespace nonplanar::test
