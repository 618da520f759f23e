#!/usr/bin/env python3
"""CTest driver: tetrefine_server with --tls_cert/--tls_key/--tls_client_ca accepts a client
certificate signed by the CA and refuses clients without one or with a foreign one."""

import argparse
import os
import subprocess
import sys
import tempfile

import grpc

from server_process import ServerProcess


def openssl(*args):
    subprocess.run(["openssl", *args], check=True, capture_output=True)


def make_ca(directory, name):
    key, cert = os.path.join(directory, name + ".key"), os.path.join(directory, name + ".pem")
    openssl("req", "-x509", "-newkey", "rsa:2048", "-nodes", "-days", "2", "-subj",
            f"/CN={name}", "-keyout", key, "-out", cert)
    return key, cert


def make_leaf(directory, name, ca, extension):
    key, csr = os.path.join(directory, name + ".key"), os.path.join(directory, name + ".csr")
    cert, ext = os.path.join(directory, name + ".pem"), os.path.join(directory, name + ".ext")
    with open(ext, "w") as f:
        f.write(extension)
    openssl("req", "-newkey", "rsa:2048", "-nodes", "-subj", f"/CN={name}", "-keyout", key,
            "-out", csr)
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
        foreign_cert = make_leaf(d, "intruder", other_ca, "extendedKeyUsage=clientAuth\n")

        flags = [f"--tls_cert={server_cert[1]}", f"--tls_key={server_cert[0]}",
                 f"--tls_client_ca={ca[1]}"]
        with ServerProcess(args.server, flags) as server:
            results = {
                "trusted client certificate": server_info(args.stubs, server.target, ca,
                                                          client_cert),
                "no client certificate": server_info(args.stubs, server.target, ca),
                "foreign client certificate": server_info(args.stubs, server.target, ca,
                                                          foreign_cert),
            }
    print("".join(server.log), end="")
    failures = []
    for case, code in results.items():
        print(f"{case}: {code}")
        expected_ok = case == "trusted client certificate"
        if (code == "OK") != expected_ok:
            failures.append(case)
    if server.exit_code != 0:
        failures.append(f"server exit code {server.exit_code}")
    if failures:
        print("failed: " + ", ".join(failures), file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
