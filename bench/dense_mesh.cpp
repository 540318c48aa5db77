#include "dense_mesh.hpp"

#include "nonplanar/io.hpp"
#include "support/solids.hpp"

namespace nonplanar::bench {

std::string write_dense_mesh(const std::filesystem::path& out, int levels) {
  const auto models = test::shared_models();
  if (models.empty()) return "../shared/models not found";
  LoadParams keep;
  keep.place_on_bed = false;
  auto base = load_mesh(models / "np_prusa_sphere.stl", keep, {});
  if (!base) return base.error().message;
  auto w = write_stl(out, test::subdivide(base->mesh, levels));
  return w ? std::string() : w.error().message;
}

}  // namespace nonplanar::bench
