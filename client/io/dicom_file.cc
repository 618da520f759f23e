#include "client/io/dicom_file.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <memory>
#include <vector>

#include "absl/strings/ascii.h"
#include "absl/strings/match.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_split.h"
#include "client/io/io_error.h"
#include "client/io/number_text.h"
#include "client/io/volume_file.h"

namespace tetrefine::io {
namespace {

constexpr uint32_t kUndefinedLength = 0xFFFFFFFFu;
constexpr uint16_t kItemGroup = 0xFFFE;
constexpr uint16_t kItem = 0xE000;
constexpr uint16_t kItemEnd = 0xE00D;
constexpr uint16_t kSequenceEnd = 0xE0DD;
// Nesting of undefined-length sequences the reader follows. Real files nest a few levels
// (a procedure code inside a request attribute); the bound keeps a hostile file from recursing
// without end.
constexpr int kMaxSequenceDepth = 32;

constexpr absl::string_view kImplicitLittle = "1.2.840.10008.1.2";
constexpr absl::string_view kExplicitLittle = "1.2.840.10008.1.2.1";

uint16_t U16(absl::string_view b, uint64_t at) {
  uint16_t v;
  std::memcpy(&v, b.data() + at, 2);
  return v;
}

uint32_t U32(absl::string_view b, uint64_t at) {
  uint32_t v;
  std::memcpy(&v, b.data() + at, 4);
  return v;
}

}  // namespace

std::string Printable(absl::string_view bytes) {
  std::string out;
  for (const char c : bytes.substr(0, 64)) {
    const unsigned char u = static_cast<unsigned char>(c);
    if (u >= 0x20 && u < 0x7f && c != '\\') {
      out.push_back(c);
    } else {
      absl::StrAppend(&out, absl::StrFormat("\\x%02x", u));
    }
  }
  if (bytes.size() > 64) out += "...";
  return out;
}

std::string TagText(uint16_t group, uint16_t element) {
  return absl::StrFormat("(%04X,%04X)", group, element);
}

namespace {

// The value representations whose explicit-VR header has two reserved bytes and a 32-bit length
// (PS3.5 7.1.2).
bool HasLongLength(const char vr[2]) {
  static constexpr const char* kLong[] = {"OB", "OD", "OF", "OL", "OV", "OW", "SQ",
                                          "SV", "UC", "UN", "UR", "UT", "UV"};
  for (const char* v : kLong) {
    if (vr[0] == v[0] && vr[1] == v[1]) return true;
  }
  return false;
}

// A DICOM string value without its padding (trailing spaces or NUL, leading spaces).
absl::string_view Trimmed(absl::string_view v) {
  while (!v.empty() && (v.back() == ' ' || v.back() == '\0')) v.remove_suffix(1);
  while (!v.empty() && v.front() == ' ') v.remove_prefix(1);
  return v;
}

// What a transfer syntax is called, for the message that refuses it.
std::string TransferSyntaxName(absl::string_view uid) {
  struct Known {
    absl::string_view uid, name;
  };
  static constexpr Known kKnown[] = {
      {"1.2.840.10008.1.2.2", "explicit VR big endian"},
      {"1.2.840.10008.1.2.1.99", "deflated explicit VR little endian"},
      {"1.2.840.10008.1.2.4.50", "JPEG baseline"},
      {"1.2.840.10008.1.2.4.51", "JPEG extended"},
      {"1.2.840.10008.1.2.4.57", "JPEG lossless"},
      {"1.2.840.10008.1.2.4.70", "JPEG lossless, first-order prediction"},
      {"1.2.840.10008.1.2.4.80", "JPEG-LS lossless"},
      {"1.2.840.10008.1.2.4.81", "JPEG-LS near-lossless"},
      {"1.2.840.10008.1.2.4.90", "JPEG 2000 lossless"},
      {"1.2.840.10008.1.2.4.91", "JPEG 2000"},
      {"1.2.840.10008.1.2.5", "RLE lossless"},
  };
  for (const Known& k : kKnown) {
    if (k.uid == uid) return absl::StrCat(uid, " (", k.name, ")");
  }
  return Printable(uid);
}

struct ElementHeader {
  uint16_t group = 0;
  uint16_t element = 0;
  char vr[2] = {0, 0};  // explicit VR only; {0, 0} otherwise
  uint32_t length = 0;
  uint64_t value = 0;  // offset of the value's first byte
};

class DataSetParser {
 public:
  DataSetParser(absl::string_view bytes, absl::string_view path) : bytes_(bytes), path_(path) {}

  // The element header at `pos`. Item and delimiter tags (FFFE,xxxx) have no VR in either form.
  absl::StatusOr<ElementHeader> Header(uint64_t pos, bool explicit_vr) const {
    if (pos + 8 > bytes_.size()) return Truncated(pos, "an element's header");
    ElementHeader h;
    h.group = U16(bytes_, pos);
    h.element = U16(bytes_, pos + 2);
    if (h.group == kItemGroup || !explicit_vr) {
      h.length = U32(bytes_, pos + 4);
      h.value = pos + 8;
      return h;
    }
    h.vr[0] = bytes_[pos + 4];
    h.vr[1] = bytes_[pos + 5];
    if (!absl::ascii_isupper(static_cast<unsigned char>(h.vr[0])) ||
        !absl::ascii_isupper(static_cast<unsigned char>(h.vr[1]))) {
      return FileError(path_,
                       absl::StrCat("DICOM element ", TagText(h.group, h.element), " at byte ", pos,
                                    " has no value representation (two capital letters)"));
    }
    if (HasLongLength(h.vr)) {
      if (pos + 12 > bytes_.size()) return Truncated(pos, "an element's header");
      h.length = U32(bytes_, pos + 8);
      h.value = pos + 12;
    } else {
      h.length = U16(bytes_, pos + 6);
      h.value = pos + 8;
    }
    return h;
  }

  // The offset just past element `h`'s value, skipping a sequence of undefined length.
  absl::StatusOr<uint64_t> Skip(const ElementHeader& h, bool explicit_vr, int depth) const {
    if (h.length != kUndefinedLength) {
      if (h.value + h.length > bytes_.size()) {
        return Truncated(h.value, absl::StrCat("element ", TagText(h.group, h.element), "'s ",
                                               h.length, "-byte value"));
      }
      return h.value + h.length;
    }
    // PS3.5 7.5: only sequences (SQ; UN holding one, whose items are then implicit VR; any
    // element of an implicit-VR data set) have an undefined length.
    const bool un = h.vr[0] == 'U' && h.vr[1] == 'N';
    const bool sq = h.vr[0] == 'S' && h.vr[1] == 'Q';
    if (explicit_vr && !un && !sq) {
      return FileError(path_, absl::StrCat("DICOM element ", TagText(h.group, h.element), " (VR ",
                                           absl::string_view(h.vr, 2),
                                           ") has an undefined length, which only a sequence may "
                                           "have"));
    }
    return SkipSequence(h.value, explicit_vr && !un, depth + 1);
  }

  // Calls visit(item, header, items_explicit_vr, depth) for every element at the top level of
  // every item of sequence `h` (item counting from 0), in order; the walk skips each element
  // after its visit. An explicit-VR element that is not SQ or UN is not walked (nothing is
  // visited). Returns the offset past `h`'s value, as Skip does. Errors name where the structure
  // breaks; never reads outside the bytes.
  template <typename Visit>
  absl::StatusOr<uint64_t> ForEachItemElement(const ElementHeader& h, bool explicit_vr, int depth,
                                              Visit&& visit) const {
    const bool un = h.vr[0] == 'U' && h.vr[1] == 'N';
    const bool sq = h.vr[0] == 'S' && h.vr[1] == 'Q';
    if (explicit_vr && !un && !sq) return Skip(h, explicit_vr, depth);
    if (depth > kMaxSequenceDepth) return TooDeep(h.value);
    const bool defined = h.length != kUndefinedLength;
    if (defined && h.value + h.length > bytes_.size()) return Truncated(h.value, "a sequence");
    // PS3.5 7.5.1: the items of a UN element of undefined length are implicit VR.
    absl::StatusOr<uint64_t> end =
        WalkItems(h.value, defined ? h.value + h.length : bytes_.size(), !defined,
                  explicit_vr && !un, depth, /*into_defined_items=*/true, visit);
    if (!end.ok() || !defined) return end;
    return h.value + h.length;
  }

  absl::Status Truncated(uint64_t at, absl::string_view what) const {
    return FileError(path_, absl::StrCat("truncated DICOM file: ", what, " at byte ", at,
                                         " runs past its end (", bytes_.size(), " bytes)"));
  }

 private:
  absl::Status TooDeep(uint64_t at) const {
    return FileError(path_, absl::StrCat("DICOM sequences nest deeper than ", kMaxSequenceDepth,
                                         " levels at byte ", at));
  }

  // Skips the items of an undefined-length sequence starting at `pos`, through its delimiter.
  absl::StatusOr<uint64_t> SkipSequence(uint64_t pos, bool explicit_vr, int depth) const {
    if (depth > kMaxSequenceDepth) return TooDeep(pos);
    return WalkItems(pos, bytes_.size(), /*delimited=*/true, explicit_vr, depth,
                     /*into_defined_items=*/false,
                     [](int64_t, const ElementHeader&, bool, int) { return absl::OkStatus(); });
  }

  // The items of a sequence from `pos`: up to `end` (defined length), or through its delimiter
  // (`delimited`, undefined length; `end` is then the end of the bytes). Each element of an
  // item is visited, then skipped. Items of defined length are stepped over whole unless
  // `into_defined_items` (skipping needs only their lengths). Returns the offset past the
  // sequence.
  template <typename Visit>
  absl::StatusOr<uint64_t> WalkItems(uint64_t pos, uint64_t end, bool delimited, bool explicit_vr,
                                     int depth, bool into_defined_items, Visit&& visit) const {
    for (int64_t item = 0; pos < end; ++item) {
      absl::StatusOr<ElementHeader> ih = Header(pos, explicit_vr);
      if (!ih.ok()) return ih.status();
      if (ih->group == kItemGroup && ih->element == kSequenceEnd) return ih->value;
      if (ih->group != kItemGroup || ih->element != kItem) {
        return FileError(path_, absl::StrCat("DICOM sequence at byte ", pos, ": expected an item ",
                                             TagText(kItemGroup, kItem), ", found ",
                                             TagText(ih->group, ih->element)));
      }
      const bool item_defined = ih->length != kUndefinedLength;
      const uint64_t item_end = item_defined ? ih->value + ih->length : end;
      if (item_end > end) return Truncated(ih->value, "a sequence item");
      uint64_t e = ih->value;
      bool item_ended = item_defined;
      while (e < item_end && (!item_defined || into_defined_items)) {
        absl::StatusOr<ElementHeader> eh = Header(e, explicit_vr);
        if (!eh.ok()) return eh.status();
        if (eh->group == kItemGroup && eh->element == kItemEnd) {
          e = eh->value;
          item_ended = true;
          break;
        }
        if (eh->group == kItemGroup) {
          return FileError(path_,
                           absl::StrCat("DICOM sequence item at byte ", e, ": found ",
                                        TagText(eh->group, eh->element), " before the item's end"));
        }
        if (absl::Status st = visit(item, *eh, explicit_vr, depth); !st.ok()) return st;
        absl::StatusOr<uint64_t> next = Skip(*eh, explicit_vr, depth);
        if (!next.ok()) return next.status();
        e = *next;
      }
      if (!item_ended) return Truncated(ih->value, "a sequence item of undefined length");
      pos = item_defined ? item_end : e;
    }
    // A sequence of undefined length ends at its delimiter, never at the end of the bytes.
    if (delimited) return Truncated(pos, "a sequence of undefined length");
    return pos;
  }

  absl::string_view bytes_;
  absl::string_view path_;
};

// Attribute names for messages.
std::string Named(uint16_t group, uint16_t element, absl::string_view name) {
  return absl::StrCat(name, " ", TagText(group, element));
}

absl::StatusOr<int> UnsignedShort(absl::string_view value, absl::string_view what,
                                  absl::string_view path) {
  if (value.size() < 2) {
    return FileError(path, absl::StrCat("DICOM ", what, " has ", value.size(),
                                        " bytes, expected a 2-byte unsigned short"));
  }
  return U16(value, 0);
}

// A decimal string (DS or IS) of exactly `n` finite numbers separated by backslashes.
template <size_t n>
absl::StatusOr<std::array<double, n>> Decimals(absl::string_view value, absl::string_view what,
                                               absl::string_view path) {
  std::array<double, n> out{};
  size_t count = 0;
  for (absl::string_view word : absl::StrSplit(value, '\\')) {
    word = Trimmed(word);
    double x;
    if (count < n && (!ParseDouble(word, x) || !std::isfinite(x))) {
      return FileError(path, absl::StrCat("DICOM ", what, ": \"", Printable(word.substr(0, 40)),
                                          "\" is not a finite number"));
    }
    if (count < n) out[count] = x;
    ++count;
  }
  if (count != n) {
    return FileError(path, absl::StrCat("DICOM ", what, " has ", count, " values, expected ", n));
  }
  return out;
}

}  // namespace

namespace {

// Whether the two bytes at `at` are a value representation of PS3.5 6.2 (explicit VR).
bool IsVr(absl::string_view bytes, size_t at) {
  static constexpr const char* kVrs[] = {"AE", "AS", "AT", "CS", "DA", "DS", "DT", "FD", "FL",
                                         "IS", "LO", "LT", "OB", "OD", "OF", "OL", "OV", "OW",
                                         "PN", "SH", "SL", "SQ", "SS", "ST", "SV", "TM", "UC",
                                         "UI", "UL", "UN", "UR", "US", "UT", "UV"};
  if (at + 2 > bytes.size()) return false;
  for (const char* v : kVrs) {
    if (bytes[at] == v[0] && bytes[at + 1] == v[1]) return true;
  }
  return false;
}

// How a file's data set begins (PS3.10 7.1, and what older software wrote without it).
enum class Framing {
  kNone,       // not recognised as DICOM
  kPart10,     // a 128-byte preamble, "DICM", the file meta group
  kMetaFirst,  // the file meta group without the preamble and "DICM"
  kBare,       // the data set alone, no file meta: its transfer syntax is inferred
};

// The first element decides. A data set written without its file meta information (ACR-NEMA
// era archives, some research exporters; pydicom and dcm2niix read these too) starts at group
// 0008 with a low element number (group length, character set, image type, SOP class); its
// syntax is explicit VR when a value representation follows the tag, else implicit VR with a
// 32-bit length that must fit in the file. Other binary files are unlikely to pass all of
// these, and one that does is refused by the parser with the element it stopped at.
Framing FramingOf(absl::string_view bytes) {
  if (bytes.size() >= 132 && bytes.substr(128, 4) == "DICM") return Framing::kPart10;
  if (bytes.size() < 8) return Framing::kNone;
  const uint16_t group = U16(bytes, 0), element = U16(bytes, 2);
  if (group == 0x0002 && element <= 0x0002 && IsVr(bytes, 4)) return Framing::kMetaFirst;
  if (group != 0x0008 || element > 0x00FF) return Framing::kNone;
  if (IsVr(bytes, 4)) return Framing::kBare;
  const uint32_t length = U32(bytes, 4);
  return length % 2 == 0 && length <= bytes.size() - 8 ? Framing::kBare : Framing::kNone;
}

// Reads the functional groups sequence `h` ((5200,9229) or (5200,9230)) into `out`, one entry
// per item, at most `max_items` (more is an error naming `limit`, what the bound is). Only the
// first item of each nested sequence counts (each holds one); other groups and attributes are
// skipped. Returns the offset past the sequence.
absl::StatusOr<uint64_t> ReadFunctionalGroups(const DataSetParser& parser, absl::string_view bytes,
                                              absl::string_view path, const ElementHeader& h,
                                              bool explicit_vr, int64_t max_items,
                                              absl::string_view limit,
                                              std::vector<DicomFrameGroups>* out) {
  const std::string sequence = TagText(h.group, h.element);
  return parser.ForEachItemElement(
      h, explicit_vr, 1,
      [&](int64_t item, const ElementHeader& group, bool items_explicit,
          int depth) -> absl::Status {
        if (item >= max_items) {
          return FileError(path, absl::StrCat("DICOM functional groups ", sequence,
                                              " has more items than ", limit));
        }
        if (static_cast<int64_t>(out->size()) <= item) out->resize(static_cast<size_t>(item) + 1);
        DicomFrameGroups& frame = (*out)[static_cast<size_t>(item)];
        const uint32_t group_tag = (uint32_t{group.group} << 16) | group.element;
        if (group_tag != 0x00209113 && group_tag != 0x00209116 && group_tag != 0x00289110 &&
            group_tag != 0x00289145) {
          return absl::OkStatus();
        }
        return parser
            .ForEachItemElement(
                group, items_explicit, depth,
                [&](int64_t inner, const ElementHeader& e, bool, int) -> absl::Status {
                  if (inner != 0 || e.length == kUndefinedLength ||
                      e.value + e.length > bytes.size()) {
                    return absl::OkStatus();  // the walk itself reports a broken length
                  }
                  const absl::string_view value = bytes.substr(e.value, e.length);
                  if (Trimmed(value).empty()) return absl::OkStatus();
                  const std::string where = absl::StrCat(" in ", sequence, " item ", item + 1, " ",
                                                         TagText(group.group, group.element));
                  const uint32_t tag = (uint32_t{e.group} << 16) | e.element;
                  if (group_tag == 0x00209113 && tag == 0x00200032) {
                    auto v = Decimals<3>(
                        value, absl::StrCat("Image Position (Patient) (0020,0032)", where), path);
                    if (!v.ok()) return v.status();
                    frame.position = *v;
                  } else if (group_tag == 0x00209116 && tag == 0x00200037) {
                    auto v = Decimals<6>(
                        value, absl::StrCat("Image Orientation (Patient) (0020,0037)", where),
                        path);
                    if (!v.ok()) return v.status();
                    frame.orientation = *v;
                  } else if (group_tag == 0x00289110 && tag == 0x00280030) {
                    auto v =
                        Decimals<2>(value, absl::StrCat("Pixel Spacing (0028,0030)", where), path);
                    if (!v.ok()) return v.status();
                    frame.pixel_spacing = *v;
                  } else if (group_tag == 0x00289145 && tag == 0x00281053) {
                    auto v =
                        Decimals<1>(value, absl::StrCat("Rescale Slope (0028,1053)", where), path);
                    if (!v.ok()) return v.status();
                    frame.rescale_slope = (*v)[0];
                  } else if (group_tag == 0x00289145 && tag == 0x00281052) {
                    auto v = Decimals<1>(
                        value, absl::StrCat("Rescale Intercept (0028,1052)", where), path);
                    if (!v.ok()) return v.status();
                    frame.rescale_intercept = (*v)[0];
                  }
                  return absl::OkStatus();
                })
            .status();
      });
}

// Keeps the first malformed NM attribute's description (DicomImage::nm_problem).
void NoteNmProblem(DicomImage& image, std::string problem) {
  if (image.nm_problem.empty()) image.nm_problem = std::move(problem);
}

// A parse error's message without the "PATH: DICOM " that FileError put before it.
std::string StatusText(const absl::Status& status, absl::string_view path) {
  absl::string_view text = status.message();
  absl::ConsumePrefix(&text, path);
  absl::ConsumePrefix(&text, ": ");
  absl::ConsumePrefix(&text, "DICOM ");
  return std::string(text);
}

// Reads the Detector Information Sequence (0054,0022) `h`: Image Position (Patient) and Image
// Orientation (Patient) of its first item into `image`, and the number of items. Returns the
// offset past the sequence.
absl::StatusOr<uint64_t> ReadDetectorInformation(const DataSetParser& parser,
                                                 absl::string_view bytes, absl::string_view path,
                                                 const ElementHeader& h, bool explicit_vr,
                                                 DicomImage* image) {
  return parser.ForEachItemElement(
      h, explicit_vr, 1, [&](int64_t item, const ElementHeader& e, bool, int) -> absl::Status {
        image->detector_items = std::max(image->detector_items, item + 1);
        if (item != 0 || e.length == kUndefinedLength || e.value + e.length > bytes.size()) {
          return absl::OkStatus();  // the walk itself reports a broken length
        }
        const absl::string_view value = bytes.substr(e.value, e.length);
        if (Trimmed(value).empty()) return absl::OkStatus();
        const std::string where = " in Detector Information Sequence (0054,0022) item 1";
        const uint32_t tag = (uint32_t{e.group} << 16) | e.element;
        // A malformed value is recorded, not refused: only the NM stacking reads these.
        if (tag == 0x00200032) {
          auto v =
              Decimals<3>(value, absl::StrCat("Image Position (Patient) (0020,0032)", where), path);
          if (v.ok()) {
            image->detector_position = *v;
          } else {
            NoteNmProblem(*image, StatusText(v.status(), path));
          }
        } else if (tag == 0x00200037) {
          auto v = Decimals<6>(
              value, absl::StrCat("Image Orientation (Patient) (0020,0037)", where), path);
          if (v.ok()) {
            image->detector_orientation = *v;
          } else {
            NoteNmProblem(*image, StatusText(v.status(), path));
          }
        }
        return absl::OkStatus();
      });
}

}  // namespace

bool HasDicomMagic(absl::string_view bytes) { return FramingOf(bytes) != Framing::kNone; }

FrameStack FrameStackOf(const DicomImage& image) {
  if (image.frames < 2) return FrameStack::kNone;
  if (image.frame_group_count() == image.frames) return FrameStack::kEnhanced;
  if (image.frame_group_count() == 0 && image.frame_increment_pointer.size() == 1 &&
      image.frame_increment_pointer[0] == kSliceVectorTag) {
    return FrameStack::kNmSlices;
  }
  return FrameStack::kNone;
}

NmStacking NmStackingOf(const DicomImage& image) {
  NmStacking out;
  if (image.spacing_between_slices && *image.spacing_between_slices != 0.0) {
    out.spacing = image.spacing_between_slices;
  } else if (image.slice_thickness && *image.slice_thickness > 0.0) {
    out.spacing = image.slice_thickness;
    out.from_thickness = true;
  }
  return out;
}

DicomImage FrameOf(const DicomImage& image, int64_t frame) {
  DicomImage out = image;
  out.pixel_data.reset();
  out.frame_groups.reset();
  out.shared_groups = DicomFrameGroups{};
  const DicomFrameGroups* own = frame >= 0 && frame < image.frame_group_count()
                                    ? &(*image.frame_groups)[static_cast<size_t>(frame)]
                                    : nullptr;
  const DicomFrameGroups& shared = image.shared_groups;
  const auto pick = [&](auto member, auto& target) {
    if (own != nullptr && (own->*member).has_value()) {
      target = *(own->*member);
    } else if ((shared.*member).has_value()) {
      target = *(shared.*member);
    }
  };
  pick(&DicomFrameGroups::position, out.position);
  pick(&DicomFrameGroups::orientation, out.orientation);
  pick(&DicomFrameGroups::pixel_spacing, out.pixel_spacing);
  pick(&DicomFrameGroups::rescale_slope, out.rescale_slope);
  pick(&DicomFrameGroups::rescale_intercept, out.rescale_intercept);
  if (FrameStackOf(image) == FrameStack::kNmSlices) {
    if (image.detector_position) out.position = image.detector_position;
    if (image.detector_orientation) out.orientation = image.detector_orientation;
    const NmStacking stacking = NmStackingOf(image);
    if (out.position && out.orientation && stacking.spacing) {
      // C.8.4.15: the slices stack along the cross product of the first row's and the first
      // column's directions, behind the first for a positive spacing.
      const std::array<double, 6>& o = *out.orientation;
      const std::array<double, 3> normal = {o[1] * o[5] - o[2] * o[4], o[2] * o[3] - o[0] * o[5],
                                            o[0] * o[4] - o[1] * o[3]};
      int64_t slice = frame;
      if (image.slice_vector && frame >= 0 &&
          frame < static_cast<int64_t>(image.slice_vector->size())) {
        slice = int64_t{(*image.slice_vector)[static_cast<size_t>(frame)]} - 1;
      }
      for (int a = 0; a < 3; ++a) {
        (*out.position)[a] += static_cast<double>(slice) * *stacking.spacing * normal[a];
      }
    }
  }
  return out;
}

absl::StatusOr<DicomImage> ParseDicomFile(absl::string_view bytes, absl::string_view path) {
  const Framing framing = FramingOf(bytes);
  if (framing == Framing::kNone) {
    return FileError(path,
                     "not a DICOM file: no \"DICM\" after a 128-byte preamble, and it does not "
                     "start with a file meta (0002,xxxx) or a group 0008 element");
  }
  DataSetParser parser(bytes, path);
  DicomImage image;
  uint64_t pos = framing == Framing::kPart10 ? 132 : 0;
  if (framing == Framing::kBare) {
    image.transfer_syntax = std::string(IsVr(bytes, 4) ? kExplicitLittle : kImplicitLittle);
  }
  // The file meta information (group 0002) is always explicit VR little endian.
  while (framing != Framing::kBare && pos + 2 <= bytes.size() && U16(bytes, pos) == 0x0002) {
    absl::StatusOr<ElementHeader> h = parser.Header(pos, /*explicit_vr=*/true);
    if (!h.ok()) return h.status();
    if (h->length == kUndefinedLength || h->value + h->length > bytes.size()) {
      return parser.Truncated(h->value,
                              absl::StrCat("file meta element ", TagText(h->group, h->element)));
    }
    const absl::string_view value = Trimmed(bytes.substr(h->value, h->length));
    if (h->element == 0x0002) image.media_sop_class = std::string(value);
    if (h->element == 0x0010) image.transfer_syntax = std::string(value);
    pos = h->value + h->length;
  }
  if (image.transfer_syntax.empty()) {
    return FileError(path, "DICOM file meta information has no Transfer Syntax UID (0002,0010)");
  }
  // The compressed syntaxes (JPEG family, JPEG-LS, JPEG 2000, RLE) keep the data set in
  // explicit VR little endian and only encapsulate the pixels: their headers are read, so that
  // a compressed image of another series (a dose screen) can be told apart and skipped, and the
  // series reader refuses one only when it is part of the series read.
  const bool encapsulated = absl::StartsWith(image.transfer_syntax, "1.2.840.10008.1.2.4.") ||
                            image.transfer_syntax == "1.2.840.10008.1.2.5";
  const bool explicit_vr = image.transfer_syntax == kExplicitLittle || encapsulated;
  const std::string refusal = absl::StrCat(
      "DICOM transfer syntax ", TransferSyntaxName(image.transfer_syntax),
      " is not read, only uncompressed little endian (", kImplicitLittle, ", ", kExplicitLittle,
      "): decompress the series with `gdcmconv --raw IN OUT` or convert it to NIfTI with "
      "dcm2niix");
  if (!explicit_vr && image.transfer_syntax != kImplicitLittle) {
    return FileUnsupported(path, refusal);
  }
  if (encapsulated) image.unsupported = refusal;
  while (pos < bytes.size()) {
    absl::StatusOr<ElementHeader> h = parser.Header(pos, explicit_vr);
    if (!h.ok()) return h.status();
    if (h->group == kItemGroup) {
      return FileError(path, absl::StrCat("DICOM item or delimiter ", TagText(h->group, h->element),
                                          " at byte ", pos, " outside any sequence"));
    }
    if (h->group == 0x7FE0 && h->element == 0x0010) {
      if (encapsulated) break;  // an image, but not one this reader decodes: `unsupported`
      if (h->length == kUndefinedLength) {
        return FileUnsupported(path,
                               "DICOM Pixel Data (7FE0,0010) is encapsulated (compressed) under "
                               "an uncompressed transfer syntax");
      }
      if (h->value + h->length > bytes.size()) {
        return parser.Truncated(h->value,
                                absl::StrCat("Pixel Data (7FE0,0010), ", h->length, " bytes,"));
      }
      image.pixel_data = bytes.substr(h->value, h->length);
      break;  // what follows the pixels (padding, signatures) places nothing
    }
    absl::StatusOr<uint64_t> next;
    const uint32_t top_tag = (uint32_t{h->group} << 16) | h->element;
    if (top_tag == 0x52009229 || top_tag == 0x52009230) {
      std::vector<DicomFrameGroups> groups;
      // Per frame: one item a frame, and never more than a volume has slices (the bound on
      // what a hostile Number of Frames makes the reader hold).
      const bool shared = top_tag == 0x52009229;
      const int64_t max_items = shared ? 1 : std::min(image.frames, kMaxVolumeAxis);
      const std::string limit =
          shared ? std::string("the one a shared group has")
          : max_items == image.frames
              ? absl::StrCat("the image's ", image.frames, " frames")
              : absl::StrCat(kMaxVolumeAxis, ", the most slices a volume has");
      // The walk that reads the groups is the one that skips them.
      next = ReadFunctionalGroups(parser, bytes, path, *h, explicit_vr, max_items, limit, &groups);
      if (!next.ok()) return next.status();
      if (top_tag == 0x52009230) {
        image.frame_groups =
            std::make_shared<const std::vector<DicomFrameGroups>>(std::move(groups));
      } else if (!groups.empty()) {
        image.shared_groups = groups.front();
      }
    } else if (top_tag == 0x00540022) {
      next = ReadDetectorInformation(parser, bytes, path, *h, explicit_vr, &image);
      if (!next.ok()) return next.status();
    } else {
      next = parser.Skip(*h, explicit_vr, 0);
      if (!next.ok()) return next.status();
    }
    // An empty value (length zero, or only padding in a text value) is an attribute left empty,
    // as anonymisers leave Rescale Slope and Intercept: absent, as dcm2niix takes it, rather than
    // a malformed number. (Binary values such as Rows are never trimmed: 32 is a space.)
    if (h->length != kUndefinedLength && h->length > 0) {
      const absl::string_view value = bytes.substr(h->value, h->length);
      const bool blank = Trimmed(value).empty();
      const uint32_t tag = (uint32_t{h->group} << 16) | h->element;
      const auto us = [&](absl::string_view name, int& out) -> absl::Status {
        absl::StatusOr<int> v = UnsignedShort(value, Named(h->group, h->element, name), path);
        if (!v.ok()) return v.status();
        out = *v;
        return absl::OkStatus();
      };
      absl::Status s;
      int us_value = 0;
      switch (tag) {
        case 0x00080018:
          image.sop_instance_uid = std::string(Trimmed(value));
          break;
        case 0x00080060:
          image.modality = std::string(Trimmed(value));
          break;
        case 0x0008103E:
          image.series_description = Printable(Trimmed(value));
          break;
        case 0x00200011:
          image.series_number = Printable(Trimmed(value));
          break;
        case 0x0020000E:
          image.series_uid = std::string(Trimmed(value));
          break;
        case 0x00200032: {
          if (blank) break;
          auto v =
              Decimals<3>(value, Named(h->group, h->element, "Image Position (Patient)"), path);
          if (!v.ok()) return v.status();
          image.position = *v;
          break;
        }
        case 0x00200037: {
          if (blank) break;
          auto v =
              Decimals<6>(value, Named(h->group, h->element, "Image Orientation (Patient)"), path);
          if (!v.ok()) return v.status();
          image.orientation = *v;
          break;
        }
        case 0x00280002:
          s = us("Samples per Pixel", image.samples_per_pixel);
          break;
        case 0x00280008: {
          if (blank) break;
          auto v = Decimals<1>(value, Named(h->group, h->element, "Number of Frames"), path);
          if (!v.ok()) return v.status();
          if ((*v)[0] < 1 || (*v)[0] != std::floor((*v)[0]) || (*v)[0] > 1e9) {
            return FileError(path, absl::StrCat("DICOM Number of Frames (0028,0008) is ", (*v)[0],
                                                ", not a positive count"));
          }
          image.frames = static_cast<int64_t>((*v)[0]);
          break;
        }
        case 0x00280009: {
          // AT: (group, element) pairs of 16-bit words. Only the NM stacking of a multi-frame
          // image reads it (Number of Frames (0028,0008) comes before it): a malformed one is
          // recorded, not refused, so that other files carrying one read as before (found by a
          // review).
          if (image.frames < 2) break;
          if (value.size() % 4 != 0) {
            NoteNmProblem(image,
                          absl::StrCat("Frame Increment Pointer (0028,0009) has ", value.size(),
                                       " bytes, not a whole number of 4-byte tags"));
            break;
          }
          image.frame_increment_pointer.clear();
          for (size_t at = 0; at < value.size(); at += 4) {
            image.frame_increment_pointer.push_back((uint32_t{U16(value, at)} << 16) |
                                                    U16(value, at + 2));
          }
          break;
        }
        case 0x00540080: {
          if (image.frames < 2) break;
          if (value.size() % 2 != 0) {
            NoteNmProblem(image, absl::StrCat("Slice Vector (0054,0080) has ", value.size(),
                                              " bytes, not 2-byte values"));
            break;
          }
          auto slices = std::make_shared<std::vector<uint16_t>>(value.size() / 2);
          for (size_t k = 0; k < slices->size(); ++k) (*slices)[k] = U16(value, 2 * k);
          image.slice_vector = std::move(slices);
          break;
        }
        // Only NM frames are stacked by these; elsewhere they place nothing, so a value that is
        // not one number (a CT series with "2.5\\2.5") is left absent rather than refused.
        case 0x00180088: {
          if (blank) break;
          auto v = Decimals<1>(value, "", path);
          if (v.ok()) image.spacing_between_slices = (*v)[0];
          break;
        }
        case 0x00180050: {
          if (blank) break;
          auto v = Decimals<1>(value, "", path);
          if (v.ok()) image.slice_thickness = (*v)[0];
          break;
        }
        case 0x00280010:
          s = us("Rows", us_value);
          image.rows = us_value;
          break;
        case 0x00280011:
          s = us("Columns", us_value);
          image.columns = us_value;
          break;
        case 0x00280030: {
          if (blank) break;
          auto v = Decimals<2>(value, Named(h->group, h->element, "Pixel Spacing"), path);
          if (!v.ok()) return v.status();
          image.pixel_spacing = *v;
          break;
        }
        case 0x00280100:
          s = us("Bits Allocated", image.bits_allocated);
          break;
        case 0x00280101:
          s = us("Bits Stored", us_value);
          image.bits_stored = us_value;
          break;
        case 0x00280103:
          s = us("Pixel Representation", image.pixel_representation);
          break;
        case 0x00281052: {
          if (blank) break;
          auto v = Decimals<1>(value, Named(h->group, h->element, "Rescale Intercept"), path);
          if (!v.ok()) return v.status();
          image.rescale_intercept = (*v)[0];
          break;
        }
        case 0x00281053: {
          if (blank) break;
          auto v = Decimals<1>(value, Named(h->group, h->element, "Rescale Slope"), path);
          if (!v.ok()) return v.status();
          image.rescale_slope = (*v)[0];
          break;
        }
        default:
          break;
      }
      if (!s.ok()) return s;
    }
    pos = *next;
  }
  return image;
}

}  // namespace tetrefine::io
