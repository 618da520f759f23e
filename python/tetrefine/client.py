"""tetrefine.Client: refine numpy arrays on a tetrefine_server."""

import os
import ssl
import tempfile
import time
from collections.abc import Mapping

import grpc

from tetrefine import _requests
from tetrefine._protocol import Protocol
from tetrefine._responses import CallbackRaised, ResponseReader
from tetrefine.errors import TetrefineError, invalid
from tetrefine.results import Record
from tetrefine.v1 import tetrefine_pb2 as pb
from tetrefine.v1 import tetrefine_pb2_grpc as pb_grpc

# Request chunk payload. The server refuses messages above its max_message_bytes (4 MiB by
# default, advertised by GetServerInfo); 1 MiB keeps every message far below that and matches
# the C++ client (client/refine_client.h), so both send the same stream.
DEFAULT_CHUNK_BYTES = 1 << 20
# Response chunks are at most 3 MiB of payload (wire/conversion.h, kMaxChunkBytes): room
# for that plus framing.
_MAX_RECEIVE_BYTES = 16 << 20
# A server that stops answering (frozen, or its host gone without a reset) left a call without a
# timeout waiting forever; pings end it with UNAVAILABLE within about 50 s, as the CLI's channel
# does. tetrefine_server accepts a ping every 10 s (server/server_setup.h).
_KEEPALIVE_TIME_MS = 30_000
_KEEPALIVE_TIMEOUT_MS = 20_000


def _read_bytes(name, value):
    if value is None or isinstance(value, bytes):
        return value
    try:
        with open(os.fspath(value), "rb") as f:
            return f.read()
    except OSError as error:
        raise invalid(f"tls[{name!r}]", f"{value}: {error.strerror}") from None


def _read_pem(name, value):
    """The bytes of a PEM entry of `tls`. gRPC takes any bytes and fails only when it connects,
    as "UNAVAILABLE: empty address list" for a CA that is not PEM (a review, 2026-11-28); the
    same check as the CLI's --tls-ca (client/cli/grpc_channel.cc) names the entry instead."""
    data = _read_bytes(name, value)
    if data is not None and b"-----BEGIN" not in data:
        raise invalid(f"tls[{name!r}]", f"{_source(value)}: not PEM (no \"-----BEGIN\" line)")
    return data


def _source(value):
    return f"{len(value)} bytes" if isinstance(value, bytes) else f"{value}"


def _check_tls_pair(tls, ca, cert, key):
    """The CLI's check of its TLS files (server/tls_files.cc) with Python's OpenSSL: a swapped
    cert and key, a key of another certificate or a key as the CA reached gRPC, which said only
    "UNAVAILABLE: empty address list" when it connected (a review, 2026-11-28)."""
    def holds_certificate(data):
        try:
            ssl.SSLContext(ssl.PROTOCOL_TLS_CLIENT).load_verify_locations(
                cadata=data.decode("latin-1"))
            return True
        except (ssl.SSLError, ValueError):
            return False

    def no_certificate(name):
        return invalid(f"tls[{name!r}]", f"{_source(tls[name])} holds no PEM certificate "
                       "(-----BEGIN CERTIFICATE-----)")

    if cert is not None:
        if not holds_certificate(cert):
            raise no_certificate("cert")
        # load_cert_chain reads files only: the PEM bytes go to a private temporary directory.
        with tempfile.TemporaryDirectory() as folder:
            cert_path, key_path = os.path.join(folder, "cert.pem"), os.path.join(folder, "key.pem")
            for path, data in ((cert_path, cert), (key_path, key)):
                with open(os.open(path, os.O_WRONLY | os.O_CREAT, 0o600), "wb") as f:
                    f.write(data)
            try:
                ssl.SSLContext(ssl.PROTOCOL_TLS_CLIENT).load_cert_chain(cert_path, key_path)
            except ssl.SSLError as error:
                if error.reason == "KEY_VALUES_MISMATCH":
                    raise invalid("tls['key']", f"{_source(tls['key'])} is not the private key "
                                  f"of the tls['cert'] certificate in {_source(tls['cert'])}"
                                  ) from None
                raise invalid("tls['key']", f"{_source(tls['key'])} holds no unencrypted PEM "
                              "private key (-----BEGIN PRIVATE KEY-----)") from None
    if ca is not None and not holds_certificate(ca):
        raise no_certificate("ca")


def _credentials(tls):
    """(channel credentials or None, extra channel options) for the `tls` argument."""
    if tls is None or tls is False:
        return None, []
    if tls is True:
        return grpc.ssl_channel_credentials(), []
    if isinstance(tls, grpc.ChannelCredentials):
        return tls, []
    if isinstance(tls, Mapping):
        unknown = set(tls) - {"ca", "cert", "key", "server_name"}
        if unknown:
            raise invalid("tls", f"unknown keys {sorted(unknown)}; expected ca, cert, key, "
                          "server_name")
        if ("cert" in tls) != ("key" in tls):
            raise invalid("tls", "a client certificate needs both 'cert' and 'key'")
        ca, key, cert = (_read_pem(name, tls.get(name)) for name in ("ca", "key", "cert"))
        _check_tls_pair(tls, ca, cert, key)
        credentials = grpc.ssl_channel_credentials(
            root_certificates=ca, private_key=key, certificate_chain=cert)
        options = []
        if tls.get("server_name"):
            options.append(("grpc.ssl_target_name_override", tls["server_name"]))
        return credentials, options
    raise invalid("tls", f"expected None, True, a dict of ca/cert/key files or "
                  f"grpc.ChannelCredentials, got {type(tls).__name__}")


# Timeouts beyond this many seconds (about 31 years) are no limit: gRPC fails a call at once
# when the deadline overflows its clock (a timeout of 1e12 or inf gave DEADLINE_EXCEEDED).
_NO_LIMIT_SECONDS = 1e9


def _timeout(value):
    """`timeout` as seconds or None (no limit); refuses NaN, negatives and non-numbers."""
    if value is None:
        return None
    seconds = _requests.real_number("timeout", value)
    if not seconds >= 0:
        raise invalid("timeout", f"must be >= 0 seconds (None: no limit), got {value!r}")
    return None if seconds > _NO_LIMIT_SECONDS else seconds


def _check_target_ports(target):
    """Refuses a numeric port outside 1-65535 in a host:port target (also "[v6]:port",
    "dns:///host:port", "ipv4:a:p,b:p"): gRPC takes 70000 modulo 65536 and connects to port
    4464, somebody else's; and a host without a port, which gRPC dials at port 0 or 443.
    unix:/path and the like, and named ports, pass. The same rule as the CLI's --server
    (client/cli/grpc_channel.cc)."""
    rest, is_list = target, False
    if rest.startswith("dns:"):
        rest = rest[4:]
        if rest.startswith("//"):  # dns://authority/host:port
            rest = rest[2:].partition("/")[2]
    elif rest.startswith(("ipv4:", "ipv6:")):
        rest, is_list = rest[5:], True
    elif "://" in rest or rest.startswith(("unix:", "unix-abstract:", "vsock:")):
        return
    for host_port in rest.split(",") if is_list else [rest]:
        if host_port.startswith("["):
            port = host_port.partition("]:")[2]
        elif host_port.count(":") == 1:
            port = host_port.partition(":")[2]
        else:  # no port, or a bare IPv6 address that cannot say where its port starts
            port = ""
        if not port:
            where = repr(target) if host_port == target else f"{host_port!r} of {target!r}"
            raise invalid("target", f"{where} has no port: write host:port "
                          "([address]:port for IPv6); tetrefine_server listens on port 50051 "
                          "unless told otherwise")
        if port.isascii() and port.isdigit() and not 1 <= int(port) <= 65535:
            raise invalid("target", f"port {port} of {target!r} is out of range (1-65535)")


class Client:
    """A connection to one tetrefine_server.

    Args:
      target: "host:port" (any gRPC target, e.g. "dns:///refiner.local:50051").
      tls: None for plaintext; True for TLS against the system's root certificates; a dict with
        "ca" (root certificate file or PEM bytes), optionally "cert" and "key" (client
        certificate for mutual TLS) and "server_name" (the name the certificate is checked
        against, when it differs from the host in `target`); or grpc.ChannelCredentials.
      token: a bearer token sent as "authorization: Bearer <token>" call metadata with every
        call, for servers that authenticate callers.

    Use as a context manager, or call close(). Safe to share between threads.
    """

    def __init__(self, target, *, tls=None, token=None):
        if not isinstance(target, str) or not target:
            raise invalid("target", f"expected a \"host:port\" string, got {target!r}")
        _check_target_ports(target)
        if token is not None and (not isinstance(token, str) or
                                  not all(" " <= c <= "~" for c in token)):
            # gRPC refuses such metadata only when a call starts, with a ValueError.
            raise invalid("token", "must be a string of printable ASCII characters (no line "
                          "breaks)")
        credentials, options = _credentials(tls)
        options = options + [
            ("grpc.max_receive_message_length", _MAX_RECEIVE_BYTES),
            ("grpc.keepalive_time_ms", _KEEPALIVE_TIME_MS),
            ("grpc.keepalive_timeout_ms", _KEEPALIVE_TIMEOUT_MS),
            # Without a limit on pings while no data flows (gRPC's default is two): a call silent
            # for a minute, then a frozen server, waited for ever (outside review, 2026-11-29).
            ("grpc.http2.max_pings_without_data", 0),
        ]
        if credentials is None:
            self._channel = grpc.insecure_channel(target, options=options)
        else:
            self._channel = grpc.secure_channel(target, credentials, options=options)
        self._stub = pb_grpc.RefinerStub(self._channel)
        self._metadata = (("authorization", f"Bearer {token}"),) if token else None
        self._protocol = Protocol(pb)
        self._chunk_bytes = None
        self._write_stall_seconds = None  # the server's, once server_info has been asked
        self.target = target

    def close(self):
        self._channel.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False

    def server_info(self, timeout=10.0):
        """The server's version and limits: Record(version, limits=Record(max_voxels,
        max_input_tets, max_output_tets, max_concurrent_refinements, max_message_bytes))."""
        timeout = _timeout(timeout)
        try:
            info = self._stub.GetServerInfo(pb.GetServerInfoRequest(), timeout=timeout,
                                            metadata=self._metadata)
        except grpc.RpcError as error:
            raise TetrefineError.from_rpc_error(error) from None
        except ValueError as error:  # grpc's own refusal, e.g. a closed channel
            raise TetrefineError(grpc.StatusCode.FAILED_PRECONDITION, str(error)) from None
        return Record.from_message(info)

    def _request_chunk_bytes(self, timeout):
        """Chunk payload that fits the server's advertised message limit (asked once)."""
        if self._chunk_bytes is None:
            try:
                info = self.server_info(timeout=timeout if timeout is not None else 30.0)
                limit = info.limits.max_message_bytes
                self._write_stall_seconds = getattr(info.limits, "write_stall_seconds", None)
            except TetrefineError as error:
                if error.code != grpc.StatusCode.UNIMPLEMENTED:
                    raise
                limit = 0
            # Half the limit leaves room for the message's framing and fields.
            chunk = DEFAULT_CHUNK_BYTES if limit <= 0 else min(DEFAULT_CHUNK_BYTES, limit // 2)
            self._chunk_bytes = max(chunk, 256)
        return self._chunk_bytes

    def refine(self, volume, spacing, origin, points, tets, epsilon, *, direction=None,
               labels=None, scheme=None, certify=False, max_iterations=None, max_tets=None,
               on_iteration=None, on_mesh=None, timeout=None, norm_coeff=None, clamp=False,
               fix_orientation=False, track_parents=False, quality_reference=None,
               lattice_n=None, lattice_max_tets=None, lattice_seed=None, min_edge_length=None,
               min_quality=None):
        """Refines the tet mesh (points, tets) immersed in a voxel volume.

        Args:
          volume: 3-d numpy array indexed [x, y, z] (any memory order). uint8, int16, uint16,
            int32, float32 and float64 travel as they are; other integer and float dtypes as the
            smallest of those that holds every value exactly (bool/int8 widen, float16 ->
            float32, int64/uint32/uint64 -> int32 when the values fit, else float64).
          spacing: 3 positive numbers, world distance between samples along x, y, z (mm).
          origin: 3 numbers, world position of sample [0, 0, 0] (mm).
          points: (n, 3) world coordinates of the mesh vertices (mm); must lie in the volume's
            box [origin, origin + (shape - 1) * spacing] unless clamp=True.
          tets: (m, 4) integer vertex indices, positively oriented unless fix_orientation=True:
            dot(p1 - p0, cross(p2 - p0, p3 - p0)) > 0.
          epsilon: relative tolerance of the edge-midpoint error (paper eq. 3), > 0.
          direction: 3x3 matrix whose columns are the unit world directions of the volume's
            x, y, z index axes (for an oblique volume; the voxel size goes in spacing, so from
            an affine pass affine[:3, :3] / spacing); None or the identity for an axis-aligned
            one.
          labels: (m,) integer label per tet, inherited by every child tet.
          scheme: "longest-edge" (reaches epsilon with bounded quality) or "paper" (the
            published scheme, unchanged); None: the server's default (longest-edge).
          certify: refine until the lattice error of every tet is at most epsilon; the result's
            certified_max_error gives the maximum over every tet.
          track_parents: also return, per output tet, the input tet it lies in (result.parent).
          max_iterations: iterations at most (server default 32).
          max_tets: stop before an iteration that would exceed this many tets.
          on_iteration: called with each IterationStats as soon as that iteration has finished
            on the server. If it raises, the call is cancelled and the exception propagates.
            Responses are read only between callbacks: one that takes longer than the
            server's write_stall_seconds (60 s by default) while the server has more to send
            gets the call cancelled (CANCELLED, with a message that says so).
          on_mesh: called with each iteration's mesh (an IterationMesh: iteration, points, tets,
            values, labels) as soon as it has arrived, right after that iteration's
            on_iteration; the server then streams every iteration's mesh (as the CLI's
            --every-iteration). The last iteration's mesh comes here too, before the result.
            Raising cancels the call, as for on_iteration.
          timeout: seconds for the whole call (DEADLINE_EXCEEDED after that); None (or inf):
            no limit.
          norm_coeff: normCoeff of eq. 3 (default: the volume's max - min).
          clamp: sample vertices outside the volume at the nearest point of its grid (indices
            clamped; for a sheared grid not always the nearest world point).
          fix_orientation: flip inverted tets instead of refusing them.
          quality_reference: the mean ratio in (0, 1] the longest-edge scheme keeps new tets at
            half of where it can (default: the input's worst tet; pass the first input's when
            refining a result again).
          lattice_n: order of the final lattice check, (n+1)(n+2)(n+3)/6 points a tet (server
            default 8; 0 skips it); lattice_max_tets: results with more tets are checked on a
            random sample of this many (default 200000; 0: every tet, which a server counts at
            the tet budget against its max_lattice_points, 2e8 by default: lower max_tets to
            about 1.2 M at order 8 for it to be accepted); lattice_seed: that
            sample's seed (default 1). As the CLI's --lattice-n, --lattice-max-tets and
            --lattice-seed.
          min_edge_length: edges shorter than this (world units) are never split (default 1/64
            of the smallest voxel spacing; 0 disables it).
          min_quality: an iteration that would make a tet of mean ratio below this is not
            applied (stop reason QUALITY_FLOOR); in [0, 1), default 1e-6, or half the input's
            worst tet where that is lower.

        direction, labels, scheme and certify need a protocol that has them: without it they
        raise TetrefineError with code UNIMPLEMENTED naming the missing field.

        Returns: a RefineResult (points, tets, values, iteration, quality, labels, parent,
          iterations, stop_reason, lattice, certified_max_error, summary).
        Raises: TetrefineError with the gRPC status code and the server's message (or ours, for
          input refused before sending: INVALID_ARGUMENT naming the argument).
        """
        if on_iteration is not None and not callable(on_iteration):
            raise invalid("on_iteration", "expected a callable taking an IterationStats or None, "
                          f"got {type(on_iteration).__name__}")
        if on_mesh is not None and not callable(on_mesh):
            raise invalid("on_mesh", "expected a callable taking an IterationMesh or None, "
                          f"got {type(on_mesh).__name__}")
        inputs = _requests.Inputs(volume, spacing, origin, points, tets, direction=direction,
                                  labels=labels)
        _requests.check_features(self._protocol, inputs)
        options = _requests.build_options(
            pb, self._protocol, epsilon, max_iterations=max_iterations, max_tets=max_tets,
            scheme=scheme, certify=certify, norm_coeff=norm_coeff, clamp=clamp,
            fix_orientation=fix_orientation, track_parents=track_parents,
            quality_reference=quality_reference, lattice_n=lattice_n,
            lattice_max_tets=lattice_max_tets, lattice_seed=lattice_seed,
            min_edge_length=min_edge_length, min_quality=min_quality)
        if on_mesh is not None:
            options.stream_every_iteration = True
        timeout = _timeout(timeout)
        # One deadline for the whole call, the server-info round trip included.
        deadline = None if timeout is None else time.monotonic() + timeout
        chunk_bytes = self._request_chunk_bytes(timeout)
        remaining = None if deadline is None else max(0.0, deadline - time.monotonic())
        stream = _requests.requests(pb, self._protocol, options, inputs, chunk_bytes)
        reader = ResponseReader(self._protocol, on_iteration, on_mesh,
                                labels_sent=inputs.labels is not None)
        try:
            call = self._stub.Refine(stream, timeout=remaining, metadata=self._metadata)
        except ValueError as error:  # grpc's own refusal, e.g. a closed channel
            raise TetrefineError(grpc.StatusCode.FAILED_PRECONDITION, str(error)) from None
        try:
            for response in call:
                reader.add(response)
        except CallbackRaised as raised:
            call.cancel()
            raise raised.error from None
        except grpc.RpcError as error:
            failure = TetrefineError.from_rpc_error(error)
            if failure.code == grpc.StatusCode.CANCELLED and (on_iteration or on_mesh):
                # The server cancels a call whose client has read no response for its
                # --write_stall_seconds, and a cancel carries no message: "Cancelled on the
                # server side" alone left a slow callback's author guessing (a review,
                # 2026-11-28).
                stall = self._write_stall_seconds
                within = f"{stall:g} s" if stall else "its write_stall_seconds"
                failure = TetrefineError(failure.code, (
                    f"{failure.details}: a server cancels a call whose client reads no response "
                    f"for {within} (limits.write_stall_seconds), and responses are read only "
                    "between callbacks: keep on_iteration and on_mesh short, or hand their "
                    "work to another thread"))
            if (failure.code == grpc.StatusCode.RESOURCE_EXHAUSTED and
                    "larger than max" in failure.details and self._chunk_bytes is not None):
                # The chunk size comes from the server's limit, asked once: a server restarted
                # with a smaller --max_message_bytes refused every later call of this client
                # (an outside review). Ask again next time, and say so.
                self._chunk_bytes = None
                failure = TetrefineError(failure.code, (
                    f"{failure.details}: the server's message limit is smaller than when this "
                    "client asked for it (a restarted or different server?); the next call "
                    "asks again"))
            raise failure from None
        except BaseException:
            # on_iteration or on_mesh raised, or KeyboardInterrupt: stop the server's work too.
            call.cancel()
            raise
        return reader.result(labels_sent=inputs.labels is not None)
