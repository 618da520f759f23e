#pragma once

#include <functional>
#include <string>

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "client/io/mesh_file.h"

namespace tetrefine::io {

// Abaqus input (.inp) as Gmsh, meshio and CalculiX write it (a flat file of *NODE and *ELEMENT
// blocks), or as Abaqus/CAE writes it (parts placed by instances, below). Keywords and parameters
// are case-insensitive; "**" lines are comments; a data line ending with a comma continues on the
// next.
//   *NODE: "id, x, y, z"; ids are any distinct integers.
//   *ELEMENT, TYPE=...: C3D4 and its variants (C3D4H, C3D4T, DC3D4, ...) are the tets; other
//     volume elements (C3D10 quadratic tets, C3D8 bricks, C3D6 wedges, ...) refuse the file,
//     naming them; shells, beams, surfaces and the like are skipped.
//   Regions: element sets (*ELSET blocks, else the ELSET= of *ELEMENT blocks), taken in file
//     order, each only if it shares no tet with one taken before (Gmsh writes an elementary and a
//     physical set for the same tets: the first one written wins). A set named with a trailing
//     number ("PhysicalVolume5", "Volume1") gives that number as its label when the taken sets'
//     numbers are distinct; otherwise the sets are numbered 1, 2, ... in file order. Tets in no
//     taken set get 0. The names go to region_names (Gmsh's $PhysicalNames when written as .msh).
//     An *ELSET's data may name earlier sets (case-insensitive; *ELSET blocks or *ELEMENT's
//     ELSET=), whose elements it then holds.
// Abaqus/CAE's structured files: each *PART ... *END PART holds its own *NODE, *ELEMENT and
//   *ELSET blocks, numbered within the part; the *ASSEMBLY places parts by *INSTANCE, NAME=...,
//   PART=... (case-insensitive names), with up to two data lines: a translation "x, y, z", then a
//   rotation "ax, ay, az, bx, by, bz, degrees" about the axis from a to b (right-handed), applied
//   after the translation as the Abaqus Keywords Reference describes *INSTANCE. The mesh is every
//   instance's tets in *INSTANCE order, each with its own copy of its part's nodes (instances that
//   share faces are refused later, as any mesh with overlapping boundaries is); instances of parts
//   without tets add nothing. Regions: each instance's part sets, by the rule above, then the
//   assembly's *ELSET, INSTANCE=... sets; with more than one instance placed a part's set is
//   named after its instance ("Block-1.Core3"). The assembly's own nodes and elements (reference
//   points, connectors) are skipped. A part with tets that no instance places, an instance that
//   defines its own nodes, and a block left open are errors.
// *INCLUDE, INPUT=name (CalculiX decks keep their mesh in one): the named file's lines stand in
// its place, read by `include` (ReadMesh's reads the name relative to the directory of the file it
// reads, as Abaqus and CalculiX read it relative to the job's directory); errors in them name the
// included file and its line. Nested up to 8 deep. Without `include` (the fuzzer, the server) an
// *INCLUDE is refused, saying so. Any other keyword (materials, sections, steps, boundary
// conditions) is skipped with its data lines. Errors name the file and line.
using AbaqusIncludeReader = std::function<absl::StatusOr<std::string>(absl::string_view name)>;
absl::StatusOr<MeshFile> ParseAbaqus(absl::string_view text, absl::string_view path,
                                     const AbaqusIncludeReader& include = {});

}  // namespace tetrefine::io
