"""Which optional features the generated tetrefine.v1 protocol of this package has.

The protocol grows (a refinement scheme, certified mode, per-tet labels, a volume direction), and
this package is generated from whatever proto it was built with. Rather than pin one version, the
client asks the generated message descriptors: a feature works as soon as its field exists, and
asking for it before that raises a TetrefineError with code UNIMPLEMENTED naming the field.

Expected field names (what the detection looks for):
  RefineOptions.scheme       an enum (values named like REFINE_SCHEME_PAPER) or a string
  RefineOptions.certify      bool
  VolumeHeader.direction     9 doubles (repeated double), row-major 3x3, columns = unit axes
  labels                     a request oneof field with "label" in its name whose message has
                             start_index and one repeated integer field (per-tet int32 labels);
                             optionally MeshHeader.has_labels (bool) or a *label_count field;
                             and the same kind of chunk in the response for the refined mesh.
"""

from google.protobuf import descriptor as _descriptor

_INTEGER_TYPES = {
    _descriptor.FieldDescriptor.TYPE_INT32, _descriptor.FieldDescriptor.TYPE_SINT32,
    _descriptor.FieldDescriptor.TYPE_SFIXED32, _descriptor.FieldDescriptor.TYPE_UINT32,
    _descriptor.FieldDescriptor.TYPE_FIXED32, _descriptor.FieldDescriptor.TYPE_INT64,
    _descriptor.FieldDescriptor.TYPE_SINT64, _descriptor.FieldDescriptor.TYPE_UINT64,
    _descriptor.FieldDescriptor.TYPE_SFIXED64, _descriptor.FieldDescriptor.TYPE_FIXED64,
}


def _repeated(field):
    return field.label == _descriptor.FieldDescriptor.LABEL_REPEATED


class LabelChunkKind:
    """A oneof field carrying per-tet labels in chunks: `name` in the oneof, `values` its data."""

    def __init__(self, name, values):
        self.name = name
        self.values = values


def _label_chunk(message_descriptor):
    """The label chunk field of a RefineRequest/RefineResponse `kind` oneof, or None."""
    oneof = message_descriptor.oneofs_by_name.get("kind")
    if oneof is None:
        return None
    for field in oneof.fields:
        if "label" not in field.name or field.message_type is None:
            continue
        chunk = field.message_type
        if "start_index" not in chunk.fields_by_name:
            continue
        data = [f for f in chunk.fields if _repeated(f) and f.type in _INTEGER_TYPES]
        if len(data) == 1:
            return LabelChunkKind(field.name, data[0].name)
    return None


class Protocol:
    """The optional features of one generated module (`pb`, a tetrefine_pb2)."""

    def __init__(self, pb):
        self.pb = pb
        options = pb.RefineOptions.DESCRIPTOR.fields_by_name
        self.scheme_field = options.get("scheme")
        self.certify_field = options.get("certify")
        header = pb.VolumeHeader.DESCRIPTOR.fields_by_name
        direction = header.get("direction")
        self.direction_field = (direction if direction is not None and _repeated(direction)
                                and direction.type == _descriptor.FieldDescriptor.TYPE_DOUBLE
                                else None)
        self.direction_misshapen = direction is not None and self.direction_field is None
        self.request_labels = _label_chunk(pb.RefineRequest.DESCRIPTOR)
        self.response_labels = _label_chunk(pb.RefineResponse.DESCRIPTOR)
        mesh_header = pb.MeshHeader.DESCRIPTOR.fields_by_name
        self.mesh_header_has_labels = "has_labels" in mesh_header
        self.mesh_header_label_count = next(
            (name for name in mesh_header if name.endswith("label_count")), None)

    def scheme_names(self):
        """The scheme names the protocol knows, as the CLI spells them ('paper',
        'longest-edge', ...); None for a string field."""
        field = self.scheme_field
        if field is None or field.enum_type is None:
            return None
        names = []
        for value in field.enum_type.values:
            if value.number == 0:
                continue  # UNSPECIFIED: the server's default, asked for by passing scheme=None
            names.append(_scheme_suffix(value.name, field.enum_type.name))
        return names

    def scheme_value(self, scheme):
        """The wire value for scheme name `scheme`, or None when the enum does not have it."""
        field = self.scheme_field
        if field.enum_type is None:
            return scheme
        for value in field.enum_type.values:
            wanted = scheme.lower().replace("_", "-")
            if value.number != 0 and _scheme_suffix(value.name, field.enum_type.name) == wanted:
                return value.number
        return None


def _scheme_suffix(value_name, enum_name):
    """REFINE_SCHEME_LONGEST_EDGE of enum RefineScheme -> 'longest-edge' (the enum name's
    upper-snake prefix dropped, words joined by '-' as on the command line)."""
    prefix = "".join("_" + c if c.isupper() and i else c for i, c in enumerate(enum_name))
    prefix = prefix.upper() + "_"
    name = value_name[len(prefix):] if value_name.startswith(prefix) else value_name
    return name.lower().replace("_", "-")
