// Stage io: read meshes (STL, OBJ, OFF, 3MF), repair and place them; write meshes.
#pragma once

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "nonplanar/context.hpp"
#include "nonplanar/mesh.hpp"
#include "nonplanar/status.hpp"

namespace nonplanar {

enum class MeshFormat { stl_binary, stl_ascii, obj, off, threemf };
const char* format_name(MeshFormat f);

/// Inputs of load_mesh. Angles in degrees, lengths in mm.
struct LoadParams {
  double scale = 1.0;         ///< uniform scale applied first (must be finite and > 0)
  double rotate_x_deg = 0.0;  ///< then rotations about X, Y, Z, in that order
  double rotate_y_deg = 0.0;
  double rotate_z_deg = 0.0;
  bool place_on_bed = true;  ///< XY bbox centre at bed_center, lowest point at z = 0
  Vec2 bed_center{110.0, 110.0};
  /// Weld tolerance as a fraction of the bounding-box diagonal (1e-7 of 100 mm = 0.01 µm
  /// would be too tight for float STL noise; 1e-6 closes near-coincident vertices safely).
  double weld_tolerance_rel = 1e-6;
  std::size_t max_triangles = 50'000'000;  ///< refuse larger inputs with a clear error
};

/// Output of load_mesh: the welded, consistently oriented, placed mesh and what was fixed.
struct LoadedMesh {
  TriangleMesh mesh;
  MeshDefects defects;
  MeshFormat format = MeshFormat::stl_binary;
  std::size_t input_triangles = 0;
  double weld_tolerance = 0.0;        ///< absolute, mm
  std::vector<std::string> warnings;  ///< one line each, without the file name
  PlateObjects objects;               ///< a 3MF's several objects and their faces
};

/// Read, weld, orient and place a mesh. The format is chosen by extension (.stl .obj .off
/// .3mf, case-insensitive). Errors: "FILE: what is wrong" with Status io_error,
/// parse_error or invalid_mesh; never a crash on malformed input.
Expected<LoadedMesh> load_mesh(const std::filesystem::path& file, const LoadParams& params,
                               const Context& ctx);

/// Binary STL writer (used by tests, benchmarks and later stages). Atomic.
Expected<void> write_stl(const std::filesystem::path& file, const TriangleMesh& mesh);

/// The mesh as one object of AMF XML (uncompressed), as a binary STL of it would reach a
/// slicer: coordinates rounded to float (written as that float's exact value read as a
/// double), vertices shared where their floats are equal (in order of first use by the faces,
/// indices from 0), faces whose corners collapse to one point or an edge left out (counted in
/// *collapsed if given). `metadata`: the object's (type, value) pairs, written as given (XML
/// text: no '<' or '&' in them), e.g. ("slic3r.layer_height_profile", "z;h;z;h;…"). For a
/// reader that cannot seek (a pipe: PrusaSlicer reads an STL or 3MF with fseek, an .amf.xml
/// front to back) that must also get a layer-height profile, which OBJ cannot carry.
/// `support_blockers`: volumes of the object under which PrusaSlicer generates no supports
/// (each a <volume> of its own, metadata slic3r.volume_type = SupportBlocker), their vertices
/// among the mesh's; their collapsed faces are left out too, and not counted.
std::string amf_text(const TriangleMesh& mesh, std::size_t* collapsed = nullptr,
                     const std::vector<std::pair<std::string, std::string>>& metadata = {},
                     const std::vector<TriangleMesh>& support_blockers = {});

/// A file stored beside the model in a 3MF package: its path in the package ("/Metadata/…")
/// and its bytes.
struct PackageFile {
  std::string path, content;
};

/// The one object of a 3MF as PrusaSlicer and OrcaSlicer read it.
struct Object3mf {
  std::string name;  ///< the object's name (empty: none)
  /// Per-object settings (PrusaSlicer's Metadata/Slic3r_PE_model.config, which OrcaSlicer
  /// reads too), e.g. {"layer_height", "0.2"}: they go with the object, whatever preset the
  /// user picks.
  std::vector<std::pair<std::string, std::string>> settings;
  /// Volumes of the object under which the slicer generates no supports (PrusaSlicer's
  /// volume_type SupportBlocker), in the mesh's coordinates. Their faces follow the mesh's in
  /// the object; our reader leaves them out.
  std::vector<TriangleMesh> support_blockers;
};

/// 3MF writer: one mesh object, one build item with no transform, and `extra` files (e.g.
/// PrusaSlicer's layer-height profile). Atomic. The 3MF reader (load_mesh) leaves out the
/// triangles of an object's volumes that PrusaSlicer's config marks as no part (modifiers,
/// support blockers and enforcers, negative volumes).
Expected<void> write_3mf(const std::filesystem::path& file, const TriangleMesh& mesh,
                         const std::vector<PackageFile>& extra = {}, const Object3mf& object = {});

/// The bytes of the part `name` ("Metadata/nonplanar_plan.json") of a 3MF (zip) package.
/// Errors: io_error (the file), parse_error (not a zip, or no such part), naming the file.
Expected<std::string> read_3mf_part(const std::filesystem::path& file, const std::string& name);

/// ASCII PLY with one RGB colour per face (face_colors: F entries, 0xRRGGBB). Atomic.
Expected<void> write_ply_face_colors(const std::filesystem::path& file, const TriangleMesh& mesh,
                                     const std::vector<unsigned>& face_colors);

}  // namespace nonplanar
