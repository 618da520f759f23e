// DICOM series (client/io/dicom_series.h): files built here byte by byte for each case the
// reader must place, decode or refuse, and series written by pydicom and converted by dcm2niix,
// the converter imaging pipelines use, read voxel for voxel at the same world points.

#include <sys/resource.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <functional>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "client/io/dicom_file.h"
#include "client/io/dicom_series.h"
#include "client/io/file_bytes.h"
#include "client/io/read_volume.h"
#include "gtest/gtest.h"
#include "tests/io/io_test_util.h"
#include "tests/support/child_process.h"

namespace tetrefine::io {
namespace {

using iotest::kPython;
using iotest::ScratchDir;
using iotest::WriteBytes;

constexpr char kExplicitLe[] = "1.2.840.10008.1.2.1";
constexpr char kImplicitLe[] = "1.2.840.10008.1.2";

std::string U16(uint16_t v) { return std::string(reinterpret_cast<const char*>(&v), 2); }
std::string U32(uint32_t v) { return std::string(reinterpret_cast<const char*>(&v), 4); }

bool LongLength(const std::string& vr) {
  for (const char* v : {"OB", "OW", "SQ", "UN", "UT", "OF", "OD"}) {
    if (vr == v) return true;
  }
  return false;
}

// One data element, its value padded to an even length as PS3.5 asks.
std::string Element(bool explicit_vr, uint16_t group, uint16_t element, const std::string& vr,
                    std::string value) {
  if (value.size() % 2 != 0) value.push_back(vr == "UI" || vr == "OB" ? '\0' : ' ');
  std::string out = U16(group) + U16(element);
  if (!explicit_vr) return out + U32(static_cast<uint32_t>(value.size())) + value;
  out += vr;
  if (LongLength(vr)) return out + U16(0) + U32(static_cast<uint32_t>(value.size())) + value;
  return out + U16(static_cast<uint16_t>(value.size())) + value;
}

std::string Us(bool explicit_vr, uint16_t group, uint16_t element, uint16_t v) {
  return Element(explicit_vr, group, element, "US", U16(v));
}

std::string Decimals(const std::vector<double>& v) {
  std::vector<std::string> words;
  // More digits than DS's 16 characters allow: the test's expected positions use the exact
  // doubles, and the reader does not limit the length.
  for (double x : v) words.push_back(absl::StrFormat("%.17g", x));
  return absl::StrJoin(words, "\\");
}

// A sequence of undefined length whose items (each the bytes of its elements) have undefined
// lengths too: the form the reader must walk to find the end.
std::string UndefinedSequence(bool explicit_vr, uint16_t group, uint16_t element,
                              const std::vector<std::string>& items) {
  std::string out = U16(group) + U16(element);
  out += explicit_vr ? std::string("SQ") + U16(0) + U32(0xFFFFFFFF) : U32(0xFFFFFFFF);
  for (const std::string& item : items) {
    out += U16(0xFFFE) + U16(0xE000) + U32(0xFFFFFFFF) + item;
    out += U16(0xFFFE) + U16(0xE00D) + U32(0);
  }
  return out + U16(0xFFFE) + U16(0xE0DD) + U32(0);
}

// How a file begins: Part 10, or the two forms without the preamble older software writes.
enum class Framing { kPart10, kMetaWithoutPreamble, kDataSetOnly };

struct SliceSpec {
  Framing framing = Framing::kPart10;
  bool explicit_vr = true;
  std::string transfer_syntax;  // empty: the one explicit_vr says
  std::string media_class = "1.2.840.10008.5.1.4.1.1.2";
  std::string series = "1.2.826.0.1.3680043.2.1";
  std::string sop_instance;  // (0008,0018); empty: not written
  std::array<double, 3> position = {0, 0, 0};
  std::array<double, 6> orientation = {1, 0, 0, 0, 1, 0};
  std::array<double, 2> spacing = {0.8, 0.5};  // between rows, between columns
  int rows = 4, columns = 3;
  int bits_allocated = 16, bits_stored = 16, representation = 1;
  std::optional<std::pair<double, double>> rescale;  // slope, intercept
  int frames = 1;
  int samples = 1;
  bool with_position = true;
  bool with_pixels = true;
  std::string pixels;        // raw samples; empty: rows * columns zeros
  std::string before_image;  // elements placed before group 0020 (sequences, private tags)
  // An enhanced multi-frame file: one frame per position (its Plane Position in the per-frame
  // functional groups, absent for nullopt), orientation and pixel spacing only in the shared
  // groups, `pixels` the frames one after another; sequences and items of defined length.
  std::vector<std::optional<std::array<double, 3>>> frame_positions;
  int extra_frame_items = 0;  // per-frame items beyond the frames (negative: fewer)
  // An NM multi-frame file (PS3.3 C.8.4): `frames` frames, `pixels` one after another; Frame
  // Increment Pointer `increment`, Slice Vector `slice_vector` (each when not empty), Spacing
  // Between Slices and Slice Thickness when given; position and orientation in a Detector
  // Information Sequence of undefined length instead of the top level.
  bool nm = false;
  std::vector<uint32_t> increment;
  std::vector<uint16_t> slice_vector;
  std::optional<double> spacing_between_slices, slice_thickness;
  std::string raw_increment;  // when not empty: the Frame Increment Pointer's bytes instead
  // NM: a top-level Image Position (Patient) besides the sequence's; more detector items (copies
  // of the first).
  std::optional<std::array<double, 3>> nm_top_position;
  int nm_detector_items = 1;
};

std::string DefinedItem(const std::string& elements) {
  return U16(0xFFFE) + U16(0xE000) + U32(static_cast<uint32_t>(elements.size())) + elements;
}

// A sequence of defined length holding `items` (each the bytes of its elements).
std::string DefinedSequence(bool explicit_vr, uint16_t group, uint16_t element,
                            const std::vector<std::string>& items) {
  std::string body;
  for (const std::string& item : items) body += DefinedItem(item);
  std::string out = U16(group) + U16(element);
  out += explicit_vr ? std::string("SQ") + U16(0) : std::string();
  return out + U32(static_cast<uint32_t>(body.size())) + body;
}

std::string SliceFile(const SliceSpec& s) {
  const bool ex = s.explicit_vr;
  const std::string ts =
      s.transfer_syntax.empty() ? (ex ? kExplicitLe : kImplicitLe) : s.transfer_syntax;
  std::string meta = Element(true, 0x0002, 0x0001, "OB", std::string("\0\1", 2)) +
                     Element(true, 0x0002, 0x0002, "UI", s.media_class) +
                     Element(true, 0x0002, 0x0003, "UI", "1.2.3.4.5") +
                     Element(true, 0x0002, 0x0010, "UI", ts);
  std::string file;
  if (s.framing == Framing::kPart10) file = std::string(128, '\0') + "DICM";
  if (s.framing != Framing::kDataSetOnly) {
    file += Element(true, 0x0002, 0x0000, "UL", U32(static_cast<uint32_t>(meta.size()))) + meta;
  }
  if (!s.sop_instance.empty()) file += Element(ex, 0x0008, 0x0018, "UI", s.sop_instance);
  file += Element(ex, 0x0008, 0x0060, "CS", s.nm ? "NM" : "CT");
  file += s.before_image;
  if (s.slice_thickness) {
    file += Element(ex, 0x0018, 0x0050, "DS", Decimals({*s.slice_thickness}));
  }
  if (s.spacing_between_slices) {
    file += Element(ex, 0x0018, 0x0088, "DS", Decimals({*s.spacing_between_slices}));
  }
  file += Element(ex, 0x0020, 0x000E, "UI", s.series);
  const bool enhanced = !s.frame_positions.empty();
  if (s.nm_top_position) {
    const auto& p = *s.nm_top_position;
    file += Element(ex, 0x0020, 0x0032, "DS", Decimals({p[0], p[1], p[2]}));
  }
  if (s.with_position && !enhanced && !s.nm) {
    file +=
        Element(ex, 0x0020, 0x0032, "DS", Decimals({s.position[0], s.position[1], s.position[2]}));
  }
  const std::string orientation =
      Element(ex, 0x0020, 0x0037, "DS", Decimals({s.orientation.begin(), s.orientation.end()}));
  const std::string spacing =
      Element(ex, 0x0028, 0x0030, "DS", Decimals({s.spacing[0], s.spacing[1]}));
  if (!enhanced && !s.nm) file += orientation;
  file += Us(ex, 0x0028, 0x0002, static_cast<uint16_t>(s.samples));
  const int frames = enhanced ? static_cast<int>(s.frame_positions.size()) : s.frames;
  if (frames != 1) file += Element(ex, 0x0028, 0x0008, "IS", absl::StrCat(frames));
  if (!s.increment.empty() || !s.raw_increment.empty()) {
    std::string tags = s.raw_increment;
    for (uint32_t t : s.increment) tags += U16(static_cast<uint16_t>(t >> 16)) + U16(t & 0xFFFF);
    file += Element(ex, 0x0028, 0x0009, "AT", tags);
  }
  file += Us(ex, 0x0028, 0x0010, static_cast<uint16_t>(s.rows));
  file += Us(ex, 0x0028, 0x0011, static_cast<uint16_t>(s.columns));
  if (!enhanced) file += spacing;
  file += Us(ex, 0x0028, 0x0100, static_cast<uint16_t>(s.bits_allocated));
  file += Us(ex, 0x0028, 0x0101, static_cast<uint16_t>(s.bits_stored));
  file += Us(ex, 0x0028, 0x0103, static_cast<uint16_t>(s.representation));
  if (s.rescale) {
    file += Element(ex, 0x0028, 0x1052, "DS", absl::StrCat(s.rescale->second));
    file += Element(ex, 0x0028, 0x1053, "DS", absl::StrCat(s.rescale->first));
  }
  if (enhanced) {
    // Shared: orientation, pixel measures; per frame: plane position and a private group.
    file += DefinedSequence(ex, 0x5200, 0x9229,
                            {DefinedSequence(ex, 0x0020, 0x9116, {orientation}) +
                             DefinedSequence(ex, 0x0028, 0x9110, {spacing})});
    std::vector<std::string> items;
    const int64_t count = static_cast<int64_t>(s.frame_positions.size()) + s.extra_frame_items;
    for (int64_t f = 0; f < count; ++f) {
      std::string item =
          DefinedSequence(ex, 0x0020, 0x9111, {Element(ex, 0x0020, 0x9157, "UL", U32(1))});
      const auto& p = f < static_cast<int64_t>(s.frame_positions.size())
                          ? s.frame_positions[static_cast<size_t>(f)]
                          : std::nullopt;
      if (p) {
        item += DefinedSequence(
            ex, 0x0020, 0x9113,
            {Element(ex, 0x0020, 0x0032, "DS", Decimals({(*p)[0], (*p)[1], (*p)[2]}))});
      }
      items.push_back(item);
    }
    file += DefinedSequence(ex, 0x5200, 0x9230, items);
  }
  if (s.nm) {
    std::string detector = orientation;
    if (s.with_position) {
      detector = Element(ex, 0x0020, 0x0032, "DS",
                         Decimals({s.position[0], s.position[1], s.position[2]})) +
                 detector;
    }
    file += UndefinedSequence(
        ex, 0x0054, 0x0022,
        std::vector<std::string>(static_cast<size_t>(s.nm_detector_items), detector));
  }
  if (!s.slice_vector.empty()) {
    std::string values;
    for (uint16_t v : s.slice_vector) values += U16(v);
    file += Element(ex, 0x0054, 0x0080, "US", values);
  }
  if (s.with_pixels) {
    const std::string pixels =
        s.pixels.empty()
            ? std::string(static_cast<size_t>(s.rows * s.columns * frames * s.bits_allocated / 8),
                          '\0')
            : s.pixels;
    file += Element(ex, 0x7FE0, 0x0010, s.bits_allocated == 8 ? "OB" : "OW", pixels);
  }
  return file;
}

// Pixels of a 16-bit slice from its samples, row by row.
std::string Pixels16(const std::vector<int>& v) {
  std::string out;
  for (int x : v) out += U16(static_cast<uint16_t>(x));
  return out;
}

// The value the series places at column i, row j of slice k (a different value everywhere).
int Value(int i, int j, int k) { return 100 * k + 10 * j + i - 50; }

std::vector<int> SliceValues(const SliceSpec& s, int k) {
  std::vector<int> v;
  for (int j = 0; j < s.rows; ++j) {
    for (int i = 0; i < s.columns; ++i) v.push_back(Value(i, j, k));
  }
  return v;
}

// The RAS world point of column i, row j of a slice, from its own attributes (LPS).
Vec3 WorldRas(const SliceSpec& s, int i, int j) {
  Vec3 p;
  for (int a = 0; a < 3; ++a) {
    p[a] = s.position[a] + i * s.orientation[a] * s.spacing[1] +
           j * s.orientation[3 + a] * s.spacing[0];
  }
  return {-p[0], -p[1], p[2]};
}

// Expects the volume to hold `value(i, j)` at each sample's world point of slice spec `s`.
template <typename F>
void ExpectSliceAt(const Volume& volume, const SliceSpec& s, F value) {
  for (int j = 0; j < s.rows; ++j) {
    for (int i = 0; i < s.columns; ++i) {
      const Vec3 u = volume.ContinuousIndex(WorldRas(s, i, j));
      std::array<int64_t, 3> n;
      for (int a = 0; a < 3; ++a) {
        n[a] = std::llround(u[a]);
        ASSERT_NEAR(u[a], static_cast<double>(n[a]), 1e-6) << "sample " << i << "," << j;
      }
      EXPECT_EQ(volume.At(n[0], n[1], n[2]), value(i, j)) << "sample " << i << "," << j;
    }
  }
}

// A series of `count` slices along the normal of `base`'s orientation, `step` mm apart, with an
// in-plane drift per slice (a gantry tilt) of `drift` (LPS mm).
std::vector<SliceSpec> Series(const SliceSpec& base, int count, double step,
                              std::array<double, 3> drift = {0, 0, 0}) {
  const auto& o = base.orientation;
  const std::array<double, 3> normal = {o[1] * o[5] - o[2] * o[4], o[2] * o[3] - o[0] * o[5],
                                        o[0] * o[4] - o[1] * o[3]};
  std::vector<SliceSpec> slices;
  for (int k = 0; k < count; ++k) {
    SliceSpec s = base;
    for (int a = 0; a < 3; ++a)
      s.position[a] = base.position[a] + k * (step * normal[a] + drift[a]);
    s.pixels = Pixels16(SliceValues(s, k));
    s.sop_instance = absl::StrCat(base.series, ".", k + 1);
    slices.push_back(s);
  }
  return slices;
}

// Writes the slices into `dir`, named so that name order is not position order.
void WriteSeries(const std::string& dir, const std::vector<SliceSpec>& slices) {
  std::filesystem::create_directories(dir);
  for (size_t k = 0; k < slices.size(); ++k) {
    WriteBytes(absl::StrCat(dir, "/IM", (k * 7 + 3) % 11, "_", slices.size() - k),
               SliceFile(slices[k]));
  }
}

void ExpectSeries(const Volume& volume, const std::vector<SliceSpec>& slices) {
  for (size_t k = 0; k < slices.size(); ++k) {
    ExpectSliceAt(volume, slices[k],
                  [&](int i, int j) { return Value(i, j, static_cast<int>(k)); });
  }
}

// Expects the file `bad` describes, read alone as bad.dcm, to be refused with a message naming
// the file and holding `expected`.
void ExpectRefusedFile(const SliceSpec& bad, const std::string& expected) {
  ScratchDir bad_dir;
  WriteBytes(bad_dir.File("bad.dcm"), SliceFile(bad));
  const absl::StatusOr<VolumeFile> read = ReadVolume(bad_dir.File("bad.dcm"));
  ASSERT_FALSE(read.ok());
  EXPECT_NE(read.status().message().find(expected), std::string::npos) << read.status();
  EXPECT_NE(read.status().message().find("bad.dcm"), std::string::npos) << read.status();
}

TEST(IoDicomTest, AxialSeriesIsSortedByPositionAndPlacedInRas) {
  ScratchDir dir;
  SliceSpec base;
  base.position = {-20.5, 31.25, -7};
  const std::vector<SliceSpec> slices = Series(base, 5, 1.5);
  WriteSeries(dir.File("ct"), slices);
  absl::StatusOr<VolumeFile> read = ReadVolume(dir.File("ct"));
  ASSERT_TRUE(read.ok()) << read.status();
  EXPECT_EQ(read->volume.grid().dims, (Index3{3, 4, 5}));
  EXPECT_EQ(read->volume.type(), VoxelType::kInt16);
  EXPECT_TRUE(read->volume.axis_aligned());
  EXPECT_DOUBLE_EQ(read->volume.grid().spacing[0], 0.5);
  EXPECT_DOUBLE_EQ(read->volume.grid().spacing[1], 0.8);
  EXPECT_DOUBLE_EQ(read->volume.grid().spacing[2], 1.5);
  EXPECT_TRUE(read->warnings.empty());
  ExpectSeries(read->volume, slices);
}

TEST(IoDicomTest, ImplicitVrAndNestedSequencesReadTheSame) {
  for (const bool explicit_vr : {true, false}) {
    SCOPED_TRACE(explicit_vr ? "explicit VR" : "implicit VR");
    ScratchDir dir;
    SliceSpec base;
    base.explicit_vr = explicit_vr;
    // A sequence of undefined length holding an item with a nested undefined-length sequence,
    // then one of defined length, then a private tag: all skipped.
    const std::string inner = UndefinedSequence(
        explicit_vr, 0x0008, 0x1032, {Element(explicit_vr, 0x0008, 0x0100, "SH", "CODE1")});
    std::string defined_item = Element(explicit_vr, 0x0008, 0x0104, "LO", "x");
    std::string defined = U16(0x0008) + U16(0x1140);
    const std::string item =
        U16(0xFFFE) + U16(0xE000) + U32(static_cast<uint32_t>(defined_item.size())) + defined_item;
    defined += explicit_vr ? std::string("SQ") + U16(0) + U32(static_cast<uint32_t>(item.size()))
                           : U32(static_cast<uint32_t>(item.size()));
    defined += item;
    base.before_image =
        UndefinedSequence(explicit_vr, 0x0008, 0x1111,
                          {inner + Element(explicit_vr, 0x0008, 0x1150, "UI", "1.2")}) +
        defined + Element(explicit_vr, 0x0009, 0x0010, "LO", "PRIVATE CREATOR");
    const std::vector<SliceSpec> slices = Series(base, 3, 2.0);
    WriteSeries(dir.File("s"), slices);
    absl::StatusOr<VolumeFile> read = ReadVolume(dir.File("s"));
    ASSERT_TRUE(read.ok()) << read.status();
    ExpectSeries(read->volume, slices);
  }
}

// Files without the 128-byte preamble and "DICM" (ACR-NEMA-era archives, some exporters),
// with or without their file meta group; without it the syntax is inferred from the first
// element. Each form, with either VR, reads as the Part 10 series does.
TEST(IoDicomTest, FilesWithoutPreambleReadTheSame) {
  for (const Framing framing : {Framing::kMetaWithoutPreamble, Framing::kDataSetOnly}) {
    for (const bool explicit_vr : {true, false}) {
      for (const bool with_uid : {true, false}) {
        SCOPED_TRACE(
            absl::StrCat(framing == Framing::kDataSetOnly ? "data set only" : "no preamble",
                         explicit_vr ? ", explicit VR" : ", implicit VR",
                         with_uid ? "" : ", first element (0008,0060)"));
        ScratchDir dir;
        SliceSpec base;
        base.framing = framing;
        base.explicit_vr = explicit_vr;
        std::vector<SliceSpec> slices = Series(base, 3, 2.0);
        if (!with_uid) {
          for (SliceSpec& slice : slices) slice.sop_instance.clear();
        }
        WriteSeries(dir.File("old"), slices);
        absl::StatusOr<VolumeFile> read = ReadVolume(dir.File("old"));
        ASSERT_TRUE(read.ok()) << read.status();
        ExpectSeries(read->volume, slices);
        EXPECT_TRUE(read->warnings.empty());
        // One file names its series, recognised without an extension.
        read = ReadVolume(dir.File("old/IM3_3"));
        ASSERT_TRUE(read.ok()) << read.status();
        ExpectSeries(read->volume, slices);
      }
    }
  }
  // Other binary files beside a series are still told apart and skipped.
  ScratchDir dir;
  WriteSeries(dir.File("s"), Series(SliceSpec{}, 3, 1.0));
  WriteBytes(dir.File("s/notes.bin"),
             std::string("\x08\x00\x10\x00\xff\xff\xff\x7f", 8) + std::string(100, 'x'));
  const absl::StatusOr<VolumeFile> read = ReadVolume(dir.File("s"));
  ASSERT_TRUE(read.ok()) << read.status();
  ASSERT_EQ(read->warnings.size(), 1u);
  EXPECT_NE(read->warnings[0].find("1 file"), std::string::npos) << read->warnings[0];
}

// An enhanced multi-frame file, built byte by byte with sequences of defined length: its frames
// are slices placed by their own Plane Positions, in position order whatever the frame order;
// frames that cannot be a volume are refused naming the frame.
TEST(IoDicomTest, EnhancedMultiFrameFramesAreSlices) {
  for (const bool explicit_vr : {true, false}) {
    SCOPED_TRACE(explicit_vr ? "explicit VR" : "implicit VR");
    SliceSpec base;
    base.explicit_vr = explicit_vr;
    base.orientation = {0, 1, 0, 0, 0, -1};  // sagittal
    const std::vector<SliceSpec> slices = Series(base, 4, 1.25);
    // Stored in the frame order 2, 0, 3, 1.
    const std::array<int, 4> order = {2, 0, 3, 1};
    SliceSpec file = base;
    file.pixels.clear();
    for (int k : order) {
      file.frame_positions.push_back(slices[k].position);
      file.pixels += slices[k].pixels;
    }
    ScratchDir dir;
    WriteBytes(dir.File("enhanced.dcm"), SliceFile(file));
    // A Frame Increment Pointer only the NM stacking reads, even a malformed one, changes
    // nothing here (a review found it refused).
    SliceSpec with_pointer = file;
    with_pointer.raw_increment = std::string("\x20\x00\x57\x91\x01\x02", 6);
    ScratchDir pointer_dir;
    WriteBytes(pointer_dir.File("pointer.dcm"), SliceFile(with_pointer));
    for (const std::string& path :
         {dir.File("enhanced.dcm"), dir.path(), pointer_dir.File("pointer.dcm")}) {
      absl::StatusOr<VolumeFile> read = ReadVolume(path);
      ASSERT_TRUE(read.ok()) << read.status();
      EXPECT_EQ(read->volume.grid().dims, (Index3{3, 4, 4}));
      ExpectSeries(read->volume, slices);
    }

    SliceSpec two_stacks = file;  // frames 1 and 3 (1-based) at one position
    two_stacks.frame_positions[2] = two_stacks.frame_positions[0];
    ExpectRefusedFile(two_stacks, "bad.dcm frame 1 and bad.dcm frame 3 lie at the same position");
    SliceSpec no_position = file;
    no_position.frame_positions[3].reset();
    ExpectRefusedFile(no_position, "DICOM frame 4 has no Image Position (Patient) (0020,0032)");
    SliceSpec extra = file;
    extra.extra_frame_items = 1;
    ExpectRefusedFile(extra, "(5200,9230) has more items than the image's 4 frames");
    SliceSpec fewer = file;
    fewer.extra_frame_items = -1;
    ExpectRefusedFile(fewer,
                      "holds 4 frames (Number of Frames (0028,0008)) but its Per-frame Functional "
                      "Groups Sequence (5200,9230) has 3 items: one per frame is needed");
    SliceSpec short_pixels = file;
    short_pixels.pixels.resize(short_pixels.pixels.size() - 2);
    ExpectRefusedFile(short_pixels, "its first 4 frames need 96");
  }
}

// An NM reconstruction (SPECT, PS3.3 C.8.4), built byte by byte: one file whose frames are the
// slices named by its Slice Vector, stacked from the Detector Information Sequence's position
// along the normal by Spacing Between Slices (negative: against the normal, C.8.4.15), else by
// Slice Thickness with a warning; frames that are not one volume's slices are refused naming
// what indexes them.
TEST(IoDicomTest, NmReconstructionFramesAreSlices) {
  for (const bool explicit_vr : {true, false}) {
    SCOPED_TRACE(explicit_vr ? "explicit VR" : "implicit VR");
    SliceSpec base;
    base.explicit_vr = explicit_vr;
    base.orientation = {1, 0, 0, 0, 0, -1};  // coronal: the normal is +y (LPS)
    base.position = {-30.5, 12.25, 40};
    base.nm = true;
    base.frames = 4;
    base.increment = {0x00540080};
    base.spacing_between_slices = 2.5;
    base.slice_thickness = 2.5;
    // The file's frames hold the slices `slice_vector` names (1-based; empty: frame order).
    const auto nm_file = [&](double step, std::vector<uint16_t> slice_vector) {
      const std::vector<SliceSpec> slices = Series(base, 4, step);
      SliceSpec file = base;
      file.slice_vector = slice_vector;
      for (int f = 0; f < 4; ++f) {
        file.pixels += slices[slice_vector.empty() ? f : slice_vector[f] - 1].pixels;
      }
      return std::pair{file, slices};
    };
    struct Case {
      std::string name;
      double step;
      std::vector<uint16_t> slice_vector;
      bool thickness_only = false;
    };
    for (const Case& c :
         {Case{"in order", 2.5, {1, 2, 3, 4}}, Case{"permuted", 2.5, {3, 1, 4, 2}},
          Case{"negative spacing", -2.5, {2, 4, 1, 3}}, Case{"no slice vector", 2.5, {}},
          Case{"thickness only", 2.5, {4, 3, 2, 1}, true}}) {
      SCOPED_TRACE(c.name);
      auto [file, slices] = nm_file(c.step, c.slice_vector);
      if (c.step < 0) file.spacing_between_slices = c.step;
      if (c.thickness_only) file.spacing_between_slices.reset();
      ScratchDir dir;
      WriteBytes(dir.File("spect.dcm"), SliceFile(file));
      for (const std::string& path : {dir.File("spect.dcm"), dir.path()}) {
        absl::StatusOr<VolumeFile> read = ReadVolume(path);
        ASSERT_TRUE(read.ok()) << read.status();
        EXPECT_EQ(read->volume.grid().dims, (Index3{3, 4, 4}));
        ExpectSeries(read->volume, slices);
        ASSERT_EQ(read->warnings.size(), c.thickness_only ? 1u : 0u);
        if (c.thickness_only) {
          EXPECT_NE(read->warnings[0].find("stacked by Slice Thickness (0018,0050)"),
                    std::string::npos)
              << read->warnings[0];
        }
      }
    }

    // Read, with one warning holding `expected`.
    const auto warned = [&](const SliceSpec& file, const std::string& expected) {
      ScratchDir dir;
      WriteBytes(dir.File("spect.dcm"), SliceFile(file));
      absl::StatusOr<VolumeFile> read = ReadVolume(dir.File("spect.dcm"));
      ASSERT_TRUE(read.ok()) << read.status();
      ExpectSeries(read->volume, nm_file(2.5, {1, 2, 3, 4}).second);
      ASSERT_EQ(read->warnings.size(), 1u);
      EXPECT_NE(read->warnings[0].find(expected), std::string::npos) << read->warnings[0];
    };
    const SliceSpec good = nm_file(2.5, {1, 2, 3, 4}).first;
    SliceSpec top_too = good;
    top_too.nm_top_position = {0, 0, 0};
    warned(top_too, "the sequence's places the NM slices");
    top_too.nm_top_position = good.position;  // the same position twice: nothing to say
    ScratchDir same_dir;
    WriteBytes(same_dir.File("spect.dcm"), SliceFile(top_too));
    const absl::StatusOr<VolumeFile> same = ReadVolume(same_dir.File("spect.dcm"));
    ASSERT_TRUE(same.ok()) << same.status();
    EXPECT_TRUE(same->warnings.empty());
    SliceSpec two_detectors = good;
    two_detectors.nm_detector_items = 2;
    warned(two_detectors, "(0054,0022) has 2 items; the first places the NM slices");
    SliceSpec zero_spacing = good;
    zero_spacing.spacing_between_slices = 0.0;
    warned(zero_spacing, "no usable Spacing Between Slices (0018,0088) (absent, zero or not one");

    SliceSpec no_spacing = good;
    no_spacing.spacing_between_slices.reset();
    no_spacing.slice_thickness.reset();
    ExpectRefusedFile(no_spacing,
                      "neither a usable Spacing Between Slices (0018,0088) (one non-zero number) "
                      "nor a positive");
    SliceSpec short_vector = good;
    short_vector.slice_vector = {1, 2, 3};
    ExpectRefusedFile(short_vector, "Slice Vector (0054,0080) has 3 values for 4 frames");
    SliceSpec zero_slice = good;
    zero_slice.slice_vector = {1, 0, 3, 4};
    ExpectRefusedFile(zero_slice, "Slice Vector (0054,0080) value 2 is 0, not a slice from 1 to 4");
    SliceSpec twice = good;
    twice.slice_vector = {1, 2, 2, 4};
    ExpectRefusedFile(twice, "Slice Vector (0054,0080) names slice 2 for frames 2 and 3");
    // Checked before the frames become slices: a few bytes claiming a million frames took
    // 1.1 GB before its missing pixels were seen (found by a review).
    SliceSpec hostile = good;
    hostile.frames = 1000000;
    hostile.rows = hostile.columns = 1;
    hostile.slice_vector.clear();
    hostile.pixels = U16(7);
    ExpectRefusedFile(hostile, "Pixel Data (7FE0,0010) has 2 bytes, its 1000000 frames need");
    SliceSpec broken_pointer = good;
    broken_pointer.increment.clear();
    broken_pointer.raw_increment = std::string("\x54\x00\x80\x00\x01\x02", 6);
    ExpectRefusedFile(broken_pointer,
                      "Frame Increment Pointer (0028,0009) has 6 bytes, not a whole number");
    SliceSpec gated = good;
    gated.increment = {0x00540070, 0x00540080};
    ExpectRefusedFile(
        gated,
        "holds 4 frames indexed by Time Slot Vector (0054,0070), Slice Vector (0054,0080) "
        "(Frame Increment Pointer (0028,0009)): not the slices of one volume");
    SliceSpec planar = good;
    planar.increment = {0x00540010, 0x00540020};
    ExpectRefusedFile(planar,
                      "indexed by Energy Window Vector (0054,0010), Detector Vector (0054,0020)");
    SliceSpec no_position = good;
    no_position.with_position = false;
    ExpectRefusedFile(
        no_position,
        "DICOM frame 1 has no Image Position (Patient) (0020,0032) (nor does its Detector "
        "Information Sequence (0054,0022))");
    SliceSpec no_pointer = good;
    no_pointer.increment.clear();
    ExpectRefusedFile(no_pointer, "nor Frame Increment Pointer (0028,0009)");
  }
}

// Each frame's slice held a copy of the file's per-frame groups: memory quadratic in the frames
// (a sweep measured 2.3 GB for 4000 frames of 2 x 2 samples, 9 GB for 8000). Now the groups are
// shared: 6000 frames read within a bound the quadratic copy would pass 10 times over.
TEST(IoDicomTest, EnhancedFramesDoNotCopyTheFilesGroups) {
  SliceSpec file;
  file.rows = 2;
  file.columns = 2;
  const int frames = 6000;
  for (int k = 0; k < frames; ++k)
    file.frame_positions.push_back(std::array<double, 3>{0, 0, static_cast<double>(k)});
  ScratchDir dir;
  WriteBytes(dir.File("many.dcm"), SliceFile(file));
  rusage before;
  getrusage(RUSAGE_SELF, &before);
  const absl::StatusOr<VolumeFile> read = ReadVolume(dir.File("many.dcm"));
  rusage after;
  getrusage(RUSAGE_SELF, &after);
  ASSERT_TRUE(read.ok()) << read.status();
  EXPECT_EQ(read->volume.grid().dims, (Index3{2, 2, frames}));
  EXPECT_LT(after.ru_maxrss - before.ru_maxrss, 500 * 1024) << "kB of high-water mark added";
  // A frame's image holds no groups of its own; the file's are shared.
  absl::StatusOr<FileView> view = FileView::Open(dir.File("many.dcm"));
  ASSERT_TRUE(view.ok());
  absl::StatusOr<DicomImage> image = ParseDicomFile(view->bytes(), "many.dcm");
  ASSERT_TRUE(image.ok()) << image.status();
  EXPECT_EQ(image->frame_group_count(), frames);
  const DicomImage frame = FrameOf(*image, 17);
  EXPECT_EQ(frame.frame_groups, nullptr);
  EXPECT_EQ((*frame.position)[2], 17.0);
}

TEST(IoDicomTest, ObliqueAndTiltedSeriesKeepTheirWorldPositions) {
  ScratchDir dir;
  SliceSpec base;
  const double a = 0.4, b = -0.25;
  // Rows along a rotated x, columns along a y rotated about both.
  base.orientation = {
      std::cos(a), std::sin(a), 0, -std::sin(a) * std::cos(b), std::cos(a) * std::cos(b),
      std::sin(b)};
  base.position = {12, -40, 88.5};
  // The step along the normal plus an in-plane drift: positions sheared like a gantry tilt.
  const std::vector<SliceSpec> slices = Series(base, 4, 2.5, {0, 0.6, 0});
  WriteSeries(dir.File("tilt"), slices);
  absl::StatusOr<VolumeFile> read = ReadVolume(dir.File("tilt"));
  ASSERT_TRUE(read.ok()) << read.status();
  EXPECT_FALSE(read->volume.axis_aligned());
  ExpectSeries(read->volume, slices);
}

// Slices 1.5 mm apart with pixels of 1e5 mm: not "at one position" (the test compared the gap
// with the in-plane spacing, found by a sweep).
TEST(IoDicomTest, SlicesCloseTogetherWithHugePixelsAreDistinct) {
  ScratchDir dir;
  SliceSpec base;
  base.spacing = {1e5, 2e5};
  const std::vector<SliceSpec> slices = Series(base, 3, 1.5);
  WriteSeries(dir.File("wide"), slices);
  const absl::StatusOr<VolumeFile> read = ReadVolume(dir.File("wide"));
  ASSERT_TRUE(read.ok()) << read.status();
  EXPECT_DOUBLE_EQ(read->volume.grid().spacing[2], 1.5);
}

TEST(IoDicomTest, RescaleGivesModalityValues) {
  ScratchDir dir;
  SliceSpec base;
  base.rescale = {{2.0, -1024.0}};
  const std::vector<SliceSpec> slices = Series(base, 3, 1.0);
  WriteSeries(dir.File("hu"), slices);
  absl::StatusOr<VolumeFile> read = ReadVolume(dir.File("hu"));
  ASSERT_TRUE(read.ok()) << read.status();
  EXPECT_EQ(read->volume.type(), VoxelType::kFloat32);
  for (size_t k = 0; k < slices.size(); ++k) {
    ExpectSliceAt(read->volume, slices[k],
                  [&](int i, int j) { return 2.0 * Value(i, j, static_cast<int>(k)) - 1024.0; });
  }
  // Per-slice scalings (as PET writes them) give float64 values, each slice its own.
  std::vector<SliceSpec> pet = slices;
  for (size_t k = 0; k < pet.size(); ++k) pet[k].rescale = {{0.5 + static_cast<double>(k), 3.0}};
  WriteSeries(dir.File("pet"), pet);
  read = ReadVolume(dir.File("pet"));
  ASSERT_TRUE(read.ok()) << read.status();
  EXPECT_EQ(read->volume.type(), VoxelType::kFloat64);
  for (size_t k = 0; k < pet.size(); ++k) {
    ExpectSliceAt(read->volume, pet[k], [&](int i, int j) {
      return (0.5 + static_cast<double>(k)) * Value(i, j, static_cast<int>(k)) + 3.0;
    });
  }
}

TEST(IoDicomTest, StoredBitsAreMaskedAndSignExtended) {
  ScratchDir dir;
  // 12 of 16 bits, signed: the high nibble carries junk (old overlay bits) to be dropped.
  const std::vector<int> want = {-5, 2047, -2048, 0, 7, -1};
  for (const int representation : {0, 1}) {
    SCOPED_TRACE(representation);
    SliceSpec base;
    base.rows = 2;
    base.columns = 3;
    base.bits_stored = 12;
    base.representation = representation;
    std::vector<SliceSpec> slices;
    for (int k = 0; k < 2; ++k) {
      SliceSpec s = base;
      s.position = {0, 0, static_cast<double>(k)};
      std::vector<int> stored;
      for (int v : want) stored.push_back((v & 0x0FFF) | 0xA000);
      s.pixels = Pixels16(stored);
      slices.push_back(s);
    }
    const std::string name = dir.File(absl::StrCat("bits", representation));
    WriteSeries(name, slices);
    absl::StatusOr<VolumeFile> read = ReadVolume(name);
    ASSERT_TRUE(read.ok()) << read.status();
    ExpectSliceAt(read->volume, slices[0], [&](int i, int j) {
      const int v = want[static_cast<size_t>(j * 3 + i)];
      return representation == 1 ? v : (v & 0x0FFF);
    });
  }
}

TEST(IoDicomTest, EightBitSignedAndThirtyTwoBitUnsignedWiden) {
  ScratchDir dir;
  struct Case {
    int bits, representation;
    VoxelType type;
    std::vector<int64_t> values;
  };
  for (const Case& c : {Case{8, 1, VoxelType::kInt16, {-128, 127, -1, 0, 5, -7}},
                        Case{8, 0, VoxelType::kUint8, {0, 255, 1, 128, 5, 7}},
                        Case{32, 0, VoxelType::kFloat64, {4000000000, 0, 1, 2147483648, 5, 7}},
                        Case{32, 1, VoxelType::kInt32, {-2000000000, 0, 1, 2000000000, 5, -7}}}) {
    SCOPED_TRACE(absl::StrCat(c.bits, " bits, representation ", c.representation));
    SliceSpec base;
    base.rows = 2;
    base.columns = 3;
    base.bits_allocated = c.bits;
    base.bits_stored = c.bits;
    base.representation = c.representation;
    std::vector<SliceSpec> slices;
    for (int k = 0; k < 2; ++k) {
      SliceSpec s = base;
      s.position = {0, 0, 3.0 * k};
      for (int64_t v : c.values) {
        const uint64_t bits = static_cast<uint64_t>(v);
        s.pixels += std::string(reinterpret_cast<const char*>(&bits), c.bits / 8);
      }
      slices.push_back(s);
    }
    const std::string name = dir.File(absl::StrCat("w", c.bits, "_", c.representation));
    WriteSeries(name, slices);
    absl::StatusOr<VolumeFile> read = ReadVolume(name);
    ASSERT_TRUE(read.ok()) << read.status();
    EXPECT_EQ(read->volume.type(), c.type);
    ExpectSliceAt(read->volume, slices[1], [&](int i, int j) {
      return static_cast<double>(c.values[static_cast<size_t>(j * 3 + i)]);
    });
  }
}

TEST(IoDicomTest, AFileSelectsItsSeriesAndADirectoryMustHoldOne) {
  ScratchDir dir;
  SliceSpec a, b;
  b.series = "1.2.826.0.1.3680043.2.99";
  b.position = {5, 5, 5};
  const std::vector<SliceSpec> first = Series(a, 3, 1.0), second = Series(b, 4, 2.0);
  const std::string d = dir.File("mixed");
  std::filesystem::create_directories(d);
  for (size_t k = 0; k < first.size(); ++k)
    WriteBytes(absl::StrCat(d, "/a", k), SliceFile(first[k]));
  for (size_t k = 0; k < second.size(); ++k) {
    WriteBytes(absl::StrCat(d, "/b", k, ".dcm"), SliceFile(second[k]));
  }
  absl::StatusOr<VolumeFile> read = ReadVolume(d);
  ASSERT_FALSE(read.ok());
  EXPECT_NE(read.status().message().find("holds 2 DICOM series"), std::string::npos)
      << read.status();
  EXPECT_NE(read.status().message().find("1.2.826.0.1.3680043.2.99: 4 images"), std::string::npos)
      << read.status();
  read = ReadVolume(d + "/b2.dcm");
  ASSERT_TRUE(read.ok()) << read.status();
  EXPECT_EQ(read->volume.grid().dims[2], 4);
  ExpectSeries(read->volume, second);
  // A file without an extension is recognised by its magic.
  read = ReadVolume(d + "/a1");
  ASSERT_TRUE(read.ok()) << read.status();
  ExpectSeries(read->volume, first);
}

TEST(IoDicomTest, OtherFilesAreSkippedWithAWarning) {
  ScratchDir dir;
  const std::vector<SliceSpec> slices = Series(SliceSpec{}, 3, 1.0);
  const std::string d = dir.File("export");
  WriteSeries(d, slices);
  WriteBytes(d + "/README.txt", "exported by a PACS\n");
  SliceSpec dicomdir;
  dicomdir.media_class = "1.2.840.10008.1.3.10";
  WriteBytes(d + "/DICOMDIR", SliceFile(dicomdir));
  SliceSpec report;
  report.with_pixels = false;
  WriteBytes(d + "/SR0001", SliceFile(report));
  std::filesystem::create_directories(d + "/subdir");
  absl::StatusOr<VolumeFile> read = ReadVolume(d);
  ASSERT_TRUE(read.ok()) << read.status();
  ExpectSeries(read->volume, slices);
  ASSERT_EQ(read->warnings.size(), 1u);
  EXPECT_NE(read->warnings[0].find("skipped 1 files that are not DICOM, 2 DICOM files "
                                   "without an image"),
            std::string::npos)
      << read->warnings[0];
}

// Each broken series is refused with a message naming what is wrong.
TEST(IoDicomTest, BrokenSeriesAreRefusedNamingTheProblem) {
  struct Case {
    std::string name;
    std::function<void(std::vector<SliceSpec>&)> damage;
    std::string expected;
  };
  const std::vector<Case> cases = {
      {"a missing slice", [](auto& s) { s.erase(s.begin() + 2); },
       "slice spacing is uneven: IM10_3 and IM6_2 are 2.5 mm apart along the slice normal, where "
       "the series averages 1.667 mm"},
      {"a slice off the line", [](auto& s) { s[2].position[0] += 0.5; },
       "do not lie on one line: IM6_3 lies 0.5 mm off the line"},
      {"two slices at one position", [](auto& s) { s[3].position = s[2].position; },
       "lie at the same position"},
      {"a single slice", [](auto& s) { s.resize(1); }, "single slice"},
      {"JPEG 2000", [](auto& s) { s[1].transfer_syntax = "1.2.840.10008.1.2.4.90"; },
       "1.2.840.10008.1.2.4.90 (JPEG 2000 lossless) is not read"},
      {"multi-frame without functional groups", [](auto& s) { s[0].frames = 40; },
       "holds 40 frames (Number of Frames (0028,0008)) but no Per-frame Functional Groups"},
      {"colour", [](auto& s) { s[2].samples = 3; }, "colour images are not read"},
      {"no position", [](auto& s) { s[1].with_position = false; },
       "no Image Position (Patient) (0020,0032)"},
      {"short pixel data", [](auto& s) { s[1].pixels.resize(10); },
       "Pixel Data (7FE0,0010) has 10 bytes, the image needs 24"},
      {"slices of other sizes",
       [](auto& s) {
         s[2].rows = 5;
         s[2].pixels += "xxxxxx";
       },
       "Rows (0028,0010) is 5 here but 4"},
      {"other orientation", [](auto& s) { s[2].orientation = {0, 1, 0, -1, 0, 0}; },
       "Image Orientation (Patient) (0020,0037) value 1"},
      {"12-bit packed",
       [](auto& s) {
         for (auto& x : s) x.bits_allocated = 12;
       },
       "only 8, 16 and 32 are read"},
      {"no bits stored",
       [](auto& s) {
         for (auto& x : s) x.bits_stored = 0;
       },
       "Bits Stored (0028,0101) is 0: a sample stores from 1 to Bits Allocated (16) bits"},
      {"more bits stored than allocated",
       [](auto& s) {
         for (auto& x : s) x.bits_stored = 17;
       },
       "Bits Stored (0028,0101) is 17: a sample stores from 1 to Bits Allocated (16) bits"},
      {"slope 0",
       [](auto& s) {
         s[0].rescale = {{0.0, 1.0}};
       },
       "Rescale Slope (0028,1053) is 0"},
      {"not unit cosines",
       [](auto& s) {
         for (auto& x : s) x.orientation[0] = 2;
       },
       "not two orthogonal unit vectors"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    ScratchDir dir;
    std::vector<SliceSpec> slices = Series(SliceSpec{}, 5, 1.25);
    c.damage(slices);
    WriteSeries(dir.File("s"), slices);
    const absl::StatusOr<VolumeFile> read = ReadVolume(dir.File("s"));
    ASSERT_FALSE(read.ok());
    EXPECT_NE(read.status().message().find(c.expected), std::string::npos) << read.status();
    EXPECT_NE(read.status().message().find(dir.path()), std::string::npos) << read.status();
  }
}

// Found by a sweep: a valid series was refused for its neighbours (a JPEG dose screen of
// another series, a truncated copy, a big-endian file), an anonymiser's empty Rescale Slope and
// Intercept were refused as numbers, and a slice exported twice was called a second volume. Now
// the series reads, the warning says what was skipped, and file bytes in messages are escaped.
TEST(IoDicomTest, NeighboursDuplicatesAndEmptyValuesDoNotStopASeries) {
  ScratchDir dir;
  SliceSpec base;
  base.rescale = {{1.0, 0.0}};
  std::vector<SliceSpec> slices = Series(base, 4, 1.5);
  const std::string d = dir.File("study");
  WriteSeries(d, slices);
  // Empty Rescale Slope and Intercept: absent, so the samples keep their integer type.
  for (size_t k = 0; k < slices.size(); ++k) {
    std::string bytes = SliceFile(slices[k]);
    for (const std::string& number : {std::string("0 "), std::string("1 ")}) {
      for (const bool ex : {true}) {
        (void)ex;
        const std::string tag = U16(0x0028) + U16(number == "0 " ? 0x1052 : 0x1053);
        const size_t at = bytes.find(tag + "DS");
        ASSERT_NE(at, std::string::npos);
        bytes.replace(at, 10, tag + "DS" + U16(2) + "  ");
      }
    }
    WriteBytes(absl::StrCat(d, "/IM", (k * 7 + 3) % 11, "_", slices.size() - k), bytes);
  }
  WriteBytes(d + "/IM3_4 (1)", SliceFile(slices[0]));  // a duplicate: same SOP Instance UID
  SliceSpec screen = base;
  screen.series = "1.2.826.0.1.3680043.2.77";
  screen.transfer_syntax = "1.2.840.10008.1.2.4.50";
  WriteBytes(d + "/zz_dose_screen.dcm", SliceFile(screen));
  WriteBytes(d + "/zz_truncated.dcm", SliceFile(screen).substr(0, 300));
  SliceSpec big_endian = base;
  big_endian.transfer_syntax = "1.2.840.10008.1.2.2";
  WriteBytes(d + "/zz_big_endian.dcm", SliceFile(big_endian));
  for (const std::string& path : {d, d + "/IM3_4"}) {
    SCOPED_TRACE(path);
    absl::StatusOr<VolumeFile> read = ReadVolume(path);
    ASSERT_TRUE(read.ok()) << read.status();
    EXPECT_EQ(read->volume.type(), VoxelType::kInt16);
    ExpectSeries(read->volume, slices);
    ASSERT_EQ(read->warnings.size(), 1u);
    for (const char* text :
         {"1 duplicate images (the same SOP Instance UID)", "2 files that could not be read"}) {
      EXPECT_NE(read->warnings[0].find(text), std::string::npos) << read->warnings[0];
    }
    // A named file reads only its own series: the other series' images are not looked at.
    EXPECT_EQ(
        read->warnings[0].find("the compressed images of 1 other series") != std::string::npos,
        path == d)
        << read->warnings[0];
  }
  // The dose screen named itself is refused as compressed.
  const absl::StatusOr<VolumeFile> screen_read = ReadVolume(d + "/zz_dose_screen.dcm");
  ASSERT_FALSE(screen_read.ok());
  EXPECT_NE(screen_read.status().message().find("(JPEG baseline) is not read"), std::string::npos)
      << screen_read.status();
  // A terminal escape in a value is escaped in the message.
  SliceSpec hostile;
  hostile.before_image = Element(true, 0x0018, 0x0050, "DS", "1");
  std::string bytes = SliceFile(hostile);
  const std::string position = Decimals({0, 0, 0});
  const size_t at = bytes.find(position);
  ASSERT_NE(at, std::string::npos);
  bytes.replace(at, 1, "\x1b");
  const absl::StatusOr<DicomImage> image = ParseDicomFile(bytes, "hostile.dcm");
  ASSERT_FALSE(image.ok());
  EXPECT_EQ(image.status().message().find('\x1b'), std::string::npos) << image.status();
  EXPECT_NE(image.status().message().find("\\x1b"), std::string::npos) << image.status();
}

TEST(IoDicomTest, MalformedDataSetsAreErrorsNeverReadsOutside) {
  const std::string good = SliceFile(Series(SliceSpec{}, 1, 1.0)[0]);
  ASSERT_TRUE(ParseDicomFile(good, "x").ok());
  // Every truncation: an error or (cut inside the trailing pixels) a short Pixel Data.
  for (size_t n = 0; n < good.size(); ++n) {
    const std::string cut = good.substr(0, n);
    const absl::StatusOr<DicomImage> image = ParseDicomFile(cut, "cut.dcm");
    if (image.ok()) {
      EXPECT_FALSE(image->pixel_data.has_value() && image->pixel_data->size() >= 24) << n;
    } else {
      EXPECT_NE(image.status().message().find("cut.dcm"), std::string::npos);
    }
  }
  // Random damage to every byte after the magic.
  std::mt19937_64 rng(7);
  for (int trial = 0; trial < 3000; ++trial) {
    std::string bad = good;
    const int flips = 1 + static_cast<int>(rng() % 4);
    for (int f = 0; f < flips; ++f) {
      bad[132 + rng() % (bad.size() - 132)] = static_cast<char>(rng());
    }
    (void)ParseDicomFile(bad, "bad.dcm");
  }
  // Sequences nested past the bound.
  std::string deep = Element(true, 0x0008, 0x0100, "SH", "X");
  for (int level = 0; level < 40; ++level) deep = UndefinedSequence(true, 0x0008, 0x1111, {deep});
  SliceSpec nested;
  nested.before_image = deep;
  absl::StatusOr<DicomImage> image = ParseDicomFile(SliceFile(nested), "deep.dcm");
  ASSERT_FALSE(image.ok());
  EXPECT_NE(image.status().message().find("nest deeper than 32"), std::string::npos)
      << image.status();
  // An item outside a sequence, and an explicit element without a VR.
  SliceSpec stray;
  stray.before_image = U16(0xFFFE) + U16(0xE000) + U32(0);
  image = ParseDicomFile(SliceFile(stray), "stray.dcm");
  ASSERT_FALSE(image.ok());
  EXPECT_NE(image.status().message().find("outside any sequence"), std::string::npos);
  SliceSpec no_vr;
  no_vr.before_image = U16(0x0009) + U16(0x1001) + std::string("\x01\x02", 2) + U16(0);
  image = ParseDicomFile(SliceFile(no_vr), "novr.dcm");
  ASSERT_FALSE(image.ok());
  EXPECT_NE(image.status().message().find("(0009,1001)"), std::string::npos) << image.status();
  image = ParseDicomFile("not dicom at all", "plain.dcm");
  ASSERT_FALSE(image.ok());
  EXPECT_NE(image.status().message().find("no \"DICM\""), std::string::npos);
}

TEST(IoDicomTest, ATopDirectorySaysSubdirectoriesAreNotSearched) {
  ScratchDir dir;
  WriteSeries(dir.File("patient/series1"), Series(SliceSpec{}, 3, 1.0));
  const absl::StatusOr<VolumeFile> read = ReadVolume(dir.File("patient"));
  ASSERT_FALSE(read.ok());
  EXPECT_NE(read.status().message().find("no DICOM image found (0 files"), std::string::npos)
      << read.status();
  EXPECT_NE(read.status().message().find("subdirectories are not searched"), std::string::npos)
      << read.status();
}

// --- An independent writer and converter: pydicom writes, dcm2niix converts -------------------

bool HavePydicomAndDcm2niix() {
  return std::filesystem::exists(kPython) && std::filesystem::exists("/usr/bin/dcm2niix") &&
         testing::RunProcess({kPython, "-c", "import pydicom, numpy"}).exit_code == 0;
}

// What the pydicom scripts share: a slice's row and column directions and its normal, axial or
// rotated about two axes.
constexpr char kPyOrientation[] = R"PY(
import numpy as np
def orientation(oblique):
    r, c = np.array([1.0, 0, 0]), np.array([0, 1.0, 0])
    if oblique:
        a, b = 0.3, 0.2
        R = np.array([[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1]]) @ \
            np.array([[1, 0, 0], [0, np.cos(b), -np.sin(b)], [0, np.sin(b), np.cos(b)]])
        r, c = R[:, 0], R[:, 1]
    return r, c, np.cross(r, c)
)PY";

// Writes a CT-like series with pydicom: int16 samples with a rescale intercept, half the files
// implicit VR, names and instance numbers in neither position order; `oblique` rotates it.
constexpr char kWriteSeries[] = R"PY(
import sys, numpy as np
from pydicom.dataset import FileDataset, FileMetaDataset
from pydicom.uid import ExplicitVRLittleEndian, ImplicitVRLittleEndian, generate_uid
out, oblique, bare = sys.argv[1], sys.argv[2] == "1", sys.argv[3] == "1"
rng = np.random.default_rng(11)
rows, cols, n = 13, 9, 6
r, c, normal = orientation(oblique)
series, study, frame = generate_uid(), generate_uid(), generate_uid()
volume = rng.integers(-1000, 3000, size=(n, rows, cols)).astype(np.int16)
for k in rng.permutation(n):
    meta = FileMetaDataset()
    meta.MediaStorageSOPClassUID = "1.2.840.10008.5.1.4.1.1.2"
    meta.MediaStorageSOPInstanceUID = sop = generate_uid()
    meta.TransferSyntaxUID = ExplicitVRLittleEndian if k % 2 else ImplicitVRLittleEndian
    name = "%s/%08d" % (out, rng.integers(1e8))
    ds = FileDataset(name, {}, file_meta=meta, preamble=b"\0" * 128)
    ds.is_little_endian, ds.is_implicit_VR = True, not k % 2
    ds.SOPClassUID, ds.SOPInstanceUID = meta.MediaStorageSOPClassUID, sop
    ds.StudyInstanceUID, ds.SeriesInstanceUID, ds.FrameOfReferenceUID = study, series, frame
    ds.Modality, ds.PatientName, ds.PatientID = "CT", "Phantom", "0"
    ds.SeriesNumber, ds.InstanceNumber = 1, int(n - k)
    ds.ImageType = ["ORIGINAL", "PRIMARY", "AXIAL"]
    ds.ImagePositionPatient = ["%.6f" % x for x in np.array([-60.3, 40.2, 10.5]) + 2.5 * k * normal]
    ds.ImageOrientationPatient = ["%.8f" % x for x in list(r) + list(c)]
    ds.PixelSpacing, ds.SliceThickness = [0.7, 0.9], 2.5
    ds.Rows, ds.Columns = rows, cols
    ds.SamplesPerPixel, ds.PhotometricInterpretation = 1, "MONOCHROME2"
    ds.BitsAllocated, ds.BitsStored, ds.HighBit, ds.PixelRepresentation = 16, 16, 15, 1
    ds.RescaleIntercept, ds.RescaleSlope = -1024, 1
    ds.PixelData = volume[k].tobytes()
    if bare:  # the data set alone, as ACR-NEMA-era archives hold it
        ds.preamble, ds.file_meta = None, FileMetaDataset()
    ds.save_as(name, write_like_original=bare)
)PY";

// Runs the pydicom `script` with `dir`/series (created) and `args`, then dcm2niix on that
// directory into `dir`/converted.nii.gz.
void WriteWithPydicomAndConvert(const char* script, const ScratchDir& dir,
                                const std::vector<std::string>& args) {
  const std::string series = dir.File("series");
  std::filesystem::create_directories(series);
  std::vector<std::string> command = {kPython, "-c", std::string(kPyOrientation) + script, series};
  command.insert(command.end(), args.begin(), args.end());
  const testing::ProcessResult wrote = testing::RunProcess(command);
  ASSERT_EQ(wrote.exit_code, 0) << wrote.out << wrote.err;
  const testing::ProcessResult converted = testing::RunProcess(
      {"/usr/bin/dcm2niix", "-z", "y", "-f", "converted", "-o", dir.path(), series});
  ASSERT_EQ(converted.exit_code, 0) << converted.out << converted.err;
}

// Expects every sample of `d` to equal the sample of `n` at the same world point (which must
// be a sample point of `n`), and `count` samples in all.
void ExpectSameVoxelsAtSameWorldPoints(const Volume& d, const Volume& n, int64_t count) {
  EXPECT_EQ(d.voxel_count(), n.voxel_count());
  int64_t compared = 0;
  for (int64_t k = 0; k < d.grid().dims[2]; ++k) {
    for (int64_t j = 0; j < d.grid().dims[1]; ++j) {
      for (int64_t i = 0; i < d.grid().dims[0]; ++i) {
        const Vec3 world = WorldOfIndex(
            d.grid(), {static_cast<double>(i), static_cast<double>(j), static_cast<double>(k)});
        const Vec3 u = n.ContinuousIndex(world);
        std::array<int64_t, 3> m;
        for (int a = 0; a < 3; ++a) {
          m[a] = std::llround(u[a]);
          ASSERT_NEAR(u[a], static_cast<double>(m[a]), 1e-4) << i << " " << j << " " << k;
        }
        ASSERT_EQ(d.At(i, j, k), n.At(m[0], m[1], m[2])) << i << " " << j << " " << k;
        ++compared;
      }
    }
  }
  EXPECT_EQ(compared, count);
}

TEST(IoDicomTest, SeriesMatchDcm2niixVoxelForVoxel) {
  if (!HavePydicomAndDcm2niix()) GTEST_SKIP() << "python3-pydicom or dcm2niix is not installed";
  for (const auto& [oblique, bare] : {std::pair{false, false}, {true, false}, {false, true}}) {
    SCOPED_TRACE(absl::StrCat(oblique ? "oblique" : "axial", bare ? ", without file meta" : ""));
    ScratchDir dir;
    const std::string series = dir.File("series");
    WriteWithPydicomAndConvert(kWriteSeries, dir, {oblique ? "1" : "0", bare ? "1" : "0"});
    if (::testing::Test::HasFatalFailure()) return;
    const absl::StatusOr<VolumeFile> dicom = ReadVolume(series);
    ASSERT_TRUE(dicom.ok()) << dicom.status();
    const absl::StatusOr<VolumeFile> nifti = ReadVolume(dir.File("converted.nii.gz"));
    ASSERT_TRUE(nifti.ok()) << nifti.status();
    EXPECT_EQ(dicom->volume.axis_aligned(), !oblique);
    ExpectSameVoxelsAtSameWorldPoints(dicom->volume, nifti->volume, 13 * 9 * 6);
  }
}

// Writes an enhanced MR image with pydicom: one file, its frames stored out of position order,
// each placed by its Plane Position in the per-frame functional groups; orientation, pixel
// spacing and a rescale in the shared ones; 12 of 16 bits stored.
constexpr char kWriteEnhanced[] = R"PY(
import sys, numpy as np
from pydicom.dataset import Dataset, FileDataset, FileMetaDataset
from pydicom.sequence import Sequence
from pydicom.uid import ExplicitVRLittleEndian, ImplicitVRLittleEndian, generate_uid
out, oblique, implicit = sys.argv[1], sys.argv[2] == "1", sys.argv[3] == "1"
rng = np.random.default_rng(5)
rows, cols, n = 11, 7, 5
r, c, normal = orientation(oblique)
volume = rng.integers(0, 4000, size=(n, rows, cols)).astype(np.uint16)
order = rng.permutation(n)
meta = FileMetaDataset()
meta.MediaStorageSOPClassUID = "1.2.840.10008.5.1.4.1.1.4.1"
meta.MediaStorageSOPInstanceUID = sop = generate_uid()
meta.TransferSyntaxUID = ImplicitVRLittleEndian if implicit else ExplicitVRLittleEndian
ds = FileDataset(out + "/enhanced.dcm", {}, file_meta=meta, preamble=b"\0" * 128)
ds.is_little_endian, ds.is_implicit_VR = True, implicit
ds.SOPClassUID, ds.SOPInstanceUID = meta.MediaStorageSOPClassUID, sop
ds.StudyInstanceUID, ds.SeriesInstanceUID = generate_uid(), generate_uid()
ds.FrameOfReferenceUID = generate_uid()
ds.Modality, ds.PatientName, ds.PatientID, ds.SeriesNumber = "MR", "Phantom", "0", 3
ds.ImageType, ds.Manufacturer = ["ORIGINAL", "PRIMARY", "M", "NONE"], "Philips"
ds.Rows, ds.Columns, ds.NumberOfFrames = rows, cols, n
ds.SamplesPerPixel, ds.PhotometricInterpretation = 1, "MONOCHROME2"
ds.BitsAllocated, ds.BitsStored, ds.HighBit, ds.PixelRepresentation = 16, 12, 11, 0
po, pm, pvt = Dataset(), Dataset(), Dataset()
po.ImageOrientationPatient = ["%.8f" % x for x in list(r) + list(c)]
pm.PixelSpacing, pm.SliceThickness, pm.SpacingBetweenSlices = [0.8, 0.6], 3.0, 3.0
pvt.RescaleIntercept, pvt.RescaleSlope, pvt.RescaleType = -50, 2, "US"
shared = Dataset()
shared.PlaneOrientationSequence = Sequence([po])
shared.PixelMeasuresSequence = Sequence([pm])
shared.PixelValueTransformationSequence = Sequence([pvt])
ds.SharedFunctionalGroupsSequence = Sequence([shared])
frames = []
for k in order:
    f, pp, fc = Dataset(), Dataset(), Dataset()
    pp.ImagePositionPatient = ["%.6f" % x for x in np.array([-20.3, 14.2, 5.5]) + 3.0 * k * normal]
    fc.InStackPositionNumber, fc.StackID, fc.TemporalPositionIndex = int(k + 1), "1", 1
    f.PlanePositionSequence, f.FrameContentSequence = Sequence([pp]), Sequence([fc])
    frames.append(f)
ds.PerFrameFunctionalGroupsSequence = Sequence(frames)
ds.PixelData = np.stack([volume[k] for k in order]).tobytes()
ds.save_as(out + "/enhanced.dcm", write_like_original=False)
)PY";

TEST(IoDicomTest, EnhancedMultiFrameMatchesDcm2niixVoxelForVoxel) {
  if (!HavePydicomAndDcm2niix()) GTEST_SKIP() << "python3-pydicom or dcm2niix is not installed";
  for (const auto& [oblique, implicit] : {std::pair{false, false}, {true, false}, {true, true}}) {
    SCOPED_TRACE(absl::StrCat(oblique ? "oblique" : "axial", implicit ? ", implicit VR" : ""));
    ScratchDir dir;
    const std::string series = dir.File("series");
    WriteWithPydicomAndConvert(kWriteEnhanced, dir, {oblique ? "1" : "0", implicit ? "1" : "0"});
    if (::testing::Test::HasFatalFailure()) return;
    for (const std::string& path : {series, series + "/enhanced.dcm"}) {
      const absl::StatusOr<VolumeFile> dicom = ReadVolume(path);
      ASSERT_TRUE(dicom.ok()) << dicom.status();
      const absl::StatusOr<VolumeFile> nifti = ReadVolume(dir.File("converted.nii.gz"));
      ASSERT_TRUE(nifti.ok()) << nifti.status();
      EXPECT_EQ(dicom->volume.grid().dims, (Index3{7, 11, 5}));
      EXPECT_EQ(dicom->volume.axis_aligned(), !oblique);
      EXPECT_TRUE(dicom->warnings.empty());
      ExpectSameVoxelsAtSameWorldPoints(dicom->volume, nifti->volume, 7 * 11 * 5);
    }
  }
}

// Writes an NM reconstruction (SPECT) with pydicom: one file of RECON TOMO frames, indexed by
// Slice Vector, placed by the Detector Information Sequence and Spacing Between Slices, with a
// rescale slope. Explicit VR only: dcm2niix 1.0.20220720 does not find the Detector
// Information Sequence's position and orientation in an implicit-VR file (it places the volume
// axis-aligned about the origin), and it stacks a negative spacing along the normal regardless
// (its issue 885); the byte-built test above checks both cases against the standard.
constexpr char kWriteNm[] = R"PY(
import sys, numpy as np
from pydicom.dataset import Dataset, FileDataset, FileMetaDataset
from pydicom.sequence import Sequence
from pydicom.tag import Tag
from pydicom.uid import ExplicitVRLittleEndian, generate_uid
out, oblique = sys.argv[1], sys.argv[2] == "1"
rng = np.random.default_rng(3)
rows, cols, n = 10, 8, 6
r, c, normal = orientation(oblique)
volume = rng.integers(0, 30000, size=(n, rows, cols)).astype(np.uint16)
meta = FileMetaDataset()
meta.MediaStorageSOPClassUID = "1.2.840.10008.5.1.4.1.1.20"
meta.MediaStorageSOPInstanceUID = sop = generate_uid()
meta.TransferSyntaxUID = ExplicitVRLittleEndian
ds = FileDataset(out + "/spect.dcm", {}, file_meta=meta, preamble=b"\0" * 128)
ds.is_little_endian, ds.is_implicit_VR = True, False
ds.SOPClassUID, ds.SOPInstanceUID = meta.MediaStorageSOPClassUID, sop
ds.StudyInstanceUID, ds.SeriesInstanceUID = generate_uid(), generate_uid()
ds.FrameOfReferenceUID = generate_uid()
ds.Modality, ds.PatientName, ds.PatientID, ds.SeriesNumber = "NM", "Phantom", "0", 4
ds.ImageType = ["ORIGINAL", "PRIMARY", "RECON TOMO", "EMISSION"]
ds.Rows, ds.Columns, ds.NumberOfFrames = rows, cols, n
ds.SamplesPerPixel, ds.PhotometricInterpretation = 1, "MONOCHROME2"
ds.BitsAllocated, ds.BitsStored, ds.HighBit, ds.PixelRepresentation = 16, 16, 15, 0
ds.FrameIncrementPointer = Tag(0x0054, 0x0080)
ds.SliceVector, ds.NumberOfSlices = list(range(1, n + 1)), n
ds.PixelSpacing, ds.SliceThickness, ds.SpacingBetweenSlices = [4.42, 3.9], 4.1, 4.1
ds.RescaleSlope, ds.RescaleIntercept = 0.5, 0
det = Dataset()
det.ImagePositionPatient = ["%.6f" % x for x in [-150.3, -140.2, 33.5]]
det.ImageOrientationPatient = ["%.8f" % x for x in list(r) + list(c)]
ds.DetectorInformationSequence = Sequence([det])
ds.PixelData = volume.tobytes()
ds.save_as(out + "/spect.dcm", write_like_original=False)
)PY";

TEST(IoDicomTest, NmReconstructionMatchesDcm2niixVoxelForVoxel) {
  if (!HavePydicomAndDcm2niix()) GTEST_SKIP() << "python3-pydicom or dcm2niix is not installed";
  for (const bool oblique : {false, true}) {
    SCOPED_TRACE(oblique ? "oblique" : "axial");
    ScratchDir dir;
    const std::string series = dir.File("series");
    WriteWithPydicomAndConvert(kWriteNm, dir, {oblique ? "1" : "0"});
    if (::testing::Test::HasFatalFailure()) return;
    const absl::StatusOr<VolumeFile> dicom = ReadVolume(series + "/spect.dcm");
    ASSERT_TRUE(dicom.ok()) << dicom.status();
    const absl::StatusOr<VolumeFile> nifti = ReadVolume(dir.File("converted.nii.gz"));
    ASSERT_TRUE(nifti.ok()) << nifti.status();
    EXPECT_EQ(dicom->volume.grid().dims, (Index3{8, 10, 6}));
    EXPECT_EQ(dicom->volume.axis_aligned(), !oblique);
    EXPECT_TRUE(dicom->warnings.empty());
    ExpectSameVoxelsAtSameWorldPoints(dicom->volume, nifti->volume, 8 * 10 * 6);
  }
}

}  // namespace
}  // namespace tetrefine::io
