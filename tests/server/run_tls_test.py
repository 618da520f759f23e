#!/usr/bin/env python3
"""CTest driver: tetrefine_server with --tls_cert/--tls_key/--tls_client_ca accepts a client
certificate signed by the CA and refuses clients without one or with a foreign one;
--tls_allowed_subjects admits only the listed subjects among those (a full subject in any order
of its attributes); /metrics is served over HTTPS with the server's certificate; --local_listen
serves plaintext health checks on loopback for probes, and refuses calls there (no certificate)."""

import argparse
import os
import re
import ssl
import subprocess
import sys
import tempfile
import urllib.error
import urllib.request

import grpc

from server_process import ServerProcess


def openssl(*args):
    subprocess.run(["openssl", *args], check=True, capture_output=True)


def make_ca(directory, name):
    key, cert = os.path.join(directory, name + ".key"), os.path.join(directory, name + ".pem")
    openssl("req", "-x509", "-newkey", "rsa:2048", "-nodes", "-days", "2", "-subj",
            f"/CN={name}", "-keyout", key, "-out", cert)
    return key, cert


def make_leaf(directory, name, ca, extension, subject=None):
    key, csr = os.path.join(directory, name + ".key"), os.path.join(directory, name + ".csr")
    cert, ext = os.path.join(directory, name + ".pem"), os.path.join(directory, name + ".ext")
    with open(ext, "w") as f:
        f.write(extension)
    openssl("req", "-newkey", "rsa:2048", "-nodes", "-subj", subject or f"/CN={name}", "-keyout",
            key, "-out", csr)
    openssl("x509", "-req", "-in", csr, "-CA", ca[1], "-CAkey", ca[0], "-CAcreateserial",
            "-days", "2", "-extfile", ext, "-out", cert)
    return key, cert


def read(path):
    with open(path, "rb") as f:
        return f.read()


def server_info(stubs, target, ca, client=None):
    """Calls GetServerInfo over TLS; returns the status code name."""
    sys.path.insert(0, stubs)
    from tetrefine.v1 import tetrefine_pb2 as pb
    from tetrefine.v1 import tetrefine_pb2_grpc as pb_grpc

    credentials = grpc.ssl_channel_credentials(
        root_certificates=read(ca[1]),
        private_key=read(client[0]) if client else None,
        certificate_chain=read(client[1]) if client else None)
    with grpc.secure_channel(target, credentials) as channel:
        try:
            pb_grpc.RefinerStub(channel).GetServerInfo(pb.GetServerInfoRequest(), timeout=10)
            return "OK"
        except grpc.RpcError as error:
            return error.code().name


def fetch(url, ca=None):
    """The body at `url`, or the error's class name."""
    context = ssl.create_default_context(cafile=ca) if ca else None
    try:
        with urllib.request.urlopen(url, timeout=10, context=context) as response:
            return response.read().decode()
    except (urllib.error.URLError, ConnectionError, ssl.SSLError, OSError) as error:
        return type(error).__name__


def logged_port(log, pattern):
    for line in log:
        match = re.search(pattern, line)
        if match:
            return int(match.group(1))
    return None


def plaintext_calls(stubs, target):
    """Over plaintext: the health check (raw bytes: HealthCheckResponse{status: SERVING} is
    08 01) and GetServerInfo, as status names."""
    sys.path.insert(0, stubs)
    from tetrefine.v1 import tetrefine_pb2 as pb
    from tetrefine.v1 import tetrefine_pb2_grpc as pb_grpc

    with grpc.insecure_channel(target) as channel:
        check = channel.unary_unary("/grpc.health.v1.Health/Check",
                                    request_serializer=lambda b: b,
                                    response_deserializer=lambda b: b)
        try:
            health = "SERVING" if check(b"", timeout=10) == b"\x08\x01" else "NOT_SERVING"
        except grpc.RpcError as error:
            health = error.code().name
        try:
            pb_grpc.RefinerStub(channel).GetServerInfo(pb.GetServerInfoRequest(), timeout=10)
            info = "OK"
        except grpc.RpcError as error:
            info = error.code().name
    return health, info


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--server", required=True)
    parser.add_argument("--stubs", required=True)
    args = parser.parse_args()

    with tempfile.TemporaryDirectory() as d:
        ca = make_ca(d, "tetrefine-test-ca")
        other_ca = make_ca(d, "foreign-ca")
        server_cert = make_leaf(d, "server", ca,
                                "subjectAltName=DNS:localhost,IP:127.0.0.1\n"
                                "extendedKeyUsage=serverAuth\n")
        client_cert = make_leaf(d, "client", ca, "extendedKeyUsage=clientAuth\n")
        stranger_cert = make_leaf(d, "stranger", ca, "extendedKeyUsage=clientAuth\n")
        foreign_cert = make_leaf(d, "intruder", other_ca, "extendedKeyUsage=clientAuth\n")
        # Two attributes: gRPC prints this subject "O=acme,CN=alice"; the allow-list below
        # names it in the order people write it.
        alice_cert = make_leaf(d, "alice", ca, "extendedKeyUsage=clientAuth\n", "/CN=alice/O=acme")

        flags = [f"--tls_cert={server_cert[1]}", f"--tls_key={server_cert[0]}",
                 f"--tls_client_ca={ca[1]}", "--tls_allowed_subjects=client; CN=alice, O=acme",
                 "--metrics_listen=127.0.0.1:0", "--local_listen=127.0.0.1:0"]
        with ServerProcess(args.server, flags) as server:
            results = {
                "trusted client certificate": server_info(args.stubs, server.target, ca,
                                                          client_cert),
                "no client certificate": server_info(args.stubs, server.target, ca),
                "foreign client certificate": server_info(args.stubs, server.target, ca,
                                                          foreign_cert),
                "trusted certificate not on the allow-list": server_info(
                    args.stubs, server.target, ca, stranger_cert),
                "allowed by its full subject in another order": server_info(
                    args.stubs, server.target, ca, alice_cert),
            }
            metrics_port = logged_port(server.log, r"metrics on https://127\.0\.0\.1:(\d+)/")
            local_port = logged_port(server.log, r"plaintext local listener on 127\.0\.0\.1:(\d+)")
            https = fetch(f"https://localhost:{metrics_port}/metrics", ca[1]) if metrics_port else ""
            plain = fetch(f"http://127.0.0.1:{metrics_port}/metrics") if metrics_port else ""
            local = plaintext_calls(args.stubs, f"127.0.0.1:{local_port}") if local_port else ()
        # Client certificates required, no allow-list: the plaintext local listener, which has
        # no certificates, let any local process refine (an operator sweep).
        flags_any = [f"--tls_cert={server_cert[1]}", f"--tls_key={server_cert[0]}",
                     f"--tls_client_ca={ca[1]}", "--metrics_listen=",
                     "--local_listen=127.0.0.1:0"]
        with ServerProcess(args.server, flags_any) as any_cert:
            any_port = logged_port(any_cert.log, r"plaintext local listener on 127\.0\.0\.1:(\d+)")
            any_local = plaintext_calls(args.stubs, f"127.0.0.1:{any_port}") if any_port else ()
            any_trusted = server_info(args.stubs, any_cert.target, ca, stranger_cert)
        # Unusable TLS files stop the server at once, naming the flag and the file (gRPC's own
        # complaint came only at bind time, after the metrics endpoint had failed on them).
        garbage = os.path.join(d, "garbage.pem")
        with open(garbage, "w") as f:
            f.write("garbage\n")
        startup = {}
        for case, tls_flags, message in [
                ("a key that is not the certificate's",
                 [f"--tls_cert={server_cert[1]}", f"--tls_key={client_cert[0]}"],
                 f"--tls_key: {client_cert[0]} is not the private key of the --tls_cert"),
                ("a CA bundle without a certificate",
                 [f"--tls_cert={server_cert[1]}", f"--tls_key={server_cert[0]}",
                  f"--tls_client_ca={garbage}"],
                 f"--tls_client_ca: {garbage} holds no PEM certificate"),
                ("a key file without a key",
                 [f"--tls_cert={server_cert[1]}", f"--tls_key={garbage}"],
                 f"--tls_key: {garbage} holds no unencrypted PEM private key")]:
            run = subprocess.run([args.server, "--listen=127.0.0.1:0", "--metrics_listen=",
                                  *tls_flags], capture_output=True, text=True, timeout=30)
            startup[case] = (run.returncode, message in run.stderr, run.stderr.strip())
    print("".join(server.log), end="")
    failures = []
    for case, (code, named, stderr) in startup.items():
        print(f"startup with {case}: exit {code}, {stderr!r}")
        if code != 2 or not named:
            failures.append(f"startup with {case}")
    expected = {"trusted client certificate": "OK",
                "trusted certificate not on the allow-list": "PERMISSION_DENIED",
                "allowed by its full subject in another order": "OK"}
    for case, code in results.items():
        print(f"{case}: {code}")
        if expected.get(case) is not None:
            if code != expected[case]:
                failures.append(case)
        elif code == "OK":
            failures.append(case)
    print(f"metrics over https: {https[:60]!r}; over plain http: {plain[:60]!r}")
    if "tetrefine_refine_calls_total" not in https:
        failures.append("metrics over https with the server's certificate")
    if "tetrefine_refine_calls_total" in plain:
        failures.append("metrics also served as plain http")
    # The local listener answers probes; calls there have no certificate and are refused.
    print(f"plaintext local listener: health {local[0] if local else None}, "
          f"GetServerInfo {local[1] if local else None}")
    if local != ("SERVING", "UNAUTHENTICATED"):
        failures.append("plaintext local listener")
    print(f"client certificates without an allow-list: any trusted one {any_trusted}; local "
          f"listener: health {any_local[0] if any_local else None}, GetServerInfo "
          f"{any_local[1] if any_local else None}")
    if any_trusted != "OK":
        failures.append("a trusted certificate without an allow-list")
    if any_local != ("SERVING", "UNAUTHENTICATED"):
        failures.append("plaintext local listener with --tls_client_ca and no allow-list")
    if server.exit_code != 0:
        failures.append(f"server exit code {server.exit_code}")
    if failures:
        print("failed: " + ", ".join(failures), file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
