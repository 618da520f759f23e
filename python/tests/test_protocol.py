"""Optional protocol features: refused by name while the proto lacks them, sent as soon as it has
them (checked on stubs generated from a copy of the proto with the fields added)."""

import os
import re
import shutil
import subprocess
import sys
import textwrap

import grpc
import numpy as np
import pytest

import tetrefine
from conftest import ROOT
from meshes import box_mesh, smooth_volume
from tetrefine._protocol import Protocol
from tetrefine.v1 import tetrefine_pb2

PROTOCOL = Protocol(tetrefine_pb2)
POINTS, TETS = box_mesh((1, 1, 1), (6, 6, 6), (1, 1, 1))

# (refine() keyword, value, present in this package's protocol, the field named when missing)
FEATURES = [
    ("scheme", "paper", PROTOCOL.scheme_field is not None, "RefineOptions.scheme"),
    ("certify", True, PROTOCOL.certify_field is not None, "RefineOptions.certify"),
    ("labels", np.arange(len(TETS)), PROTOCOL.request_labels is not None,
     "label chunk in RefineRequest"),
    ("direction", np.array([[0, -1, 0], [1, 0, 0], [0, 0, 1]]),
     PROTOCOL.direction_field is not None, "VolumeHeader.direction"),
]


@pytest.mark.parametrize("keyword, value, present, field", FEATURES,
                         ids=[f[0] for f in FEATURES])
def test_a_feature_the_protocol_lacks_is_refused_by_name(server, keyword, value, present, field):
    if present:
        pytest.skip(f"the protocol has {field}; test_features_of_a_newer_protocol_are_sent "
                    "covers it")
    with tetrefine.Client(server.target) as client:
        with pytest.raises(tetrefine.TetrefineError) as error:
            client.refine(smooth_volume((8, 8, 8)), (1, 1, 1), (0, 0, 0), POINTS, TETS, 0.1,
                          **{keyword: value})
    assert error.value.code == grpc.StatusCode.UNIMPLEMENTED
    assert error.value.details.startswith(f"{keyword}: not in this package's tetrefine.v1")
    assert field in error.value.details


def test_the_identity_direction_needs_no_field(server):
    with tetrefine.Client(server.target) as client:
        result = client.refine(smooth_volume((8, 8, 8)), (1, 1, 1), (0, 0, 0), POINTS, TETS,
                               0.1, direction=np.eye(3))
    assert len(result.tets) >= len(TETS)


# Fields added to a copy of the proto, in the shapes _protocol.py documents.
_ADDITIONS = {
    "scheme_enum": ("RefineOptions", "Scheme scheme = 900;",
                    "enum Scheme {\n  SCHEME_UNSPECIFIED = 0;\n  SCHEME_PAPER = 1;\n"
                    "  SCHEME_CONVERGING = 2;\n}\n"),
    "scheme_string": ("RefineOptions", "string scheme = 900;", ""),
    "labels": (None, None, "message TetLabelChunk {\n  int64 start_index = 1;\n"
                           "  repeated int32 labels = 2;\n}\n"),
}


def _extended_proto(text, scheme):
    """The proto with every feature field added (keeping any it already has)."""
    def add_field(message, field):
        pattern = re.compile(r"(message " + message + r" \{\n)")
        return pattern.sub(lambda m: m.group(1) + "  " + field + "\n", text, count=1)

    protocol = PROTOCOL
    extra = ""
    if protocol.scheme_field is None:
        message, field, definition = _ADDITIONS[scheme]
        text, extra = add_field(message, field), extra + definition
    if protocol.certify_field is None:
        text = add_field("RefineOptions", "bool certify = 901;")
    if protocol.direction_field is None:
        text = add_field("VolumeHeader", "repeated double direction = 900;")
    if protocol.request_labels is None:
        extra += _ADDITIONS["labels"][2]
        text = text.replace("    EndOfInput end_of_input = 8;\n",
                            "    EndOfInput end_of_input = 8;\n"
                            "    TetLabelChunk tet_label_chunk = 900;\n", 1)
        text = add_field("MeshHeader", "bool has_labels = 900;")
    if protocol.response_labels is None:
        text = text.replace("    Summary summary = 8;\n",
                            "    Summary summary = 8;\n"
                            "    TetLabelChunk tet_label_chunk = 900;\n", 1)
    return text + "\n" + extra


_CHECK = textwrap.dedent("""
    import numpy as np
    import tetrefine
    from tetrefine import _requests
    from tetrefine._protocol import Protocol
    from tetrefine._responses import ResponseReader
    from tetrefine.v1 import tetrefine_pb2 as pb

    protocol = Protocol(pb)
    points = np.array([[1, 1, 1], [3, 1, 1], [1, 3, 1], [1, 1, 3.0]])
    tets = np.array([[0, 1, 2, 3]])
    direction = np.array([[0, -1, 0], [1, 0, 0], [0, 0, 1.0]])
    inputs = _requests.Inputs(np.zeros((4, 4, 4)), (1, 1, 1), (0, 0, 0), points, tets,
                              direction=direction, labels=np.array([42]))
    _requests.check_features(protocol, inputs)
    options = _requests.build_options(pb, protocol, 0.1, scheme="paper", certify=True)
    assert options.certify is True
    scheme_field = pb.RefineOptions.DESCRIPTOR.fields_by_name["scheme"]
    if scheme_field.enum_type is not None:
        paper = [v for v in scheme_field.enum_type.values if v.name.endswith("SCHEME_PAPER")]
        assert options.scheme == paper[0].number, options
        try:
            _requests.build_options(pb, protocol, 0.1, scheme="nonsense")
            raise SystemExit("an unknown scheme was accepted")
        except tetrefine.TetrefineError as error:
            known = ", ".join(protocol.scheme_names())
            assert "paper" in known, known
            assert f"unknown scheme 'nonsense'; this protocol knows {known}" in str(
                error), error
    else:
        assert options.scheme == "paper"
    stream = list(_requests.requests(pb, protocol, options, inputs, 1 << 20))
    kinds = [r.WhichOneof("kind") for r in stream]
    assert kinds == ["options", "volume_header", "volume_chunk", "mesh_header", "vertex_chunk",
                     "tet_chunk", "tet_label_chunk", "end_of_input"], kinds
    assert list(stream[1].volume_header.direction) == direction.reshape(-1).tolist()
    assert stream[3].mesh_header.has_labels
    assert list(stream[6].tet_label_chunk.labels) == [42]

    reader = ResponseReader(protocol)
    responses = [
        pb.RefineResponse(mesh_header=pb.ResultMeshHeader(
            final=True, vertex_count=4, tet_count=1, value_count=4, tet_iteration_count=1,
            tet_quality_count=1)),
        pb.RefineResponse(vertex_chunk=pb.VertexChunk(coordinates=points.ravel().tolist())),
        pb.RefineResponse(value_chunk=pb.ValueChunk(values=[0, 0, 0, 0])),
        pb.RefineResponse(tet_chunk=pb.TetChunk(indices=[0, 1, 2, 3])),
        pb.RefineResponse(tet_iteration_chunk=pb.TetIterationChunk(iterations=[0])),
        pb.RefineResponse(tet_quality_chunk=pb.TetQualityChunk(qualities=[0.5])),
        pb.RefineResponse(tet_label_chunk=pb.TetLabelChunk(labels=[42])),
        pb.RefineResponse(summary=pb.Summary(stop_reason=pb.STOP_REASON_CONVERGED)),
    ]
    for response in responses:
        reader.add(response)
    result = reader.result(labels_sent=True)
    assert result.labels.tolist() == [42] and result.stop_reason == "converged"
    print("features sent and read")
""")


@pytest.mark.parametrize("scheme", ["scheme_enum", "scheme_string"])
def test_features_of_a_newer_protocol_are_sent(tmp_path, scheme):
    proto_dir = tmp_path / "proto"
    (proto_dir / "tetrefine" / "v1").mkdir(parents=True)
    original = open(os.path.join(ROOT, "proto", "tetrefine", "v1", "tetrefine.proto")).read()
    (proto_dir / "tetrefine" / "v1" / "tetrefine.proto").write_text(
        _extended_proto(original, scheme))
    package = tmp_path / "pkg" / "tetrefine"
    shutil.copytree(os.path.join(ROOT, "python", "tetrefine"), package,
                    ignore=shutil.ignore_patterns("__pycache__"))
    generate = [sys.executable, os.path.join(ROOT, "python", "tools", "generate_stubs.py"),
                "--proto-dir", str(proto_dir), "--package-dir", str(package / "v1")]
    subprocess.run(generate, check=True, capture_output=True)
    done = subprocess.run([sys.executable, "-c", _CHECK], capture_output=True, text=True,
                          env=dict(os.environ, PYTHONPATH=str(tmp_path / "pkg")), cwd=tmp_path)
    assert done.returncode == 0, done.stdout + done.stderr
    assert "features sent and read" in done.stdout
