#!/usr/bin/env python3
"""CTest driver: the Dockerfile, the Kubernetes manifests and compose.yaml parse, carry what a
deployment of tetrefine_server needs, and agree with each other and with the server's own flag
defaults (read from the built binary's --helpfull)."""

import argparse
import glob
import os
import re
import subprocess
import sys

sys.dont_write_bytecode = True  # no __pycache__ in the source tree

import yaml

import dockerfile_parse

failures = []


def check(condition, message):
    if not condition:
        failures.append(message)
    return condition


def flag_defaults(server):
    """{flag: default} from the server's --helpfull."""
    run = subprocess.run([server, "--helpfull"], capture_output=True, text=True, timeout=30)
    text = run.stdout + run.stderr
    defaults = {}
    # One block per flag: "--name (help...); default: value;" over one or more lines.
    for block in re.split(r"\n(?=\s*--\w)", text):
        match = re.match(r"\s*--(\w+) .*default: \"?(.*?)\"?;", block, re.S)
        if match:
            defaults[match.group(1)] = match.group(2)
    return defaults


def port_of(address):
    return int(address.rsplit(":", 1)[1])


def check_dockerfile(path, grpc_port, metrics_port):
    with open(path) as f:
        stages = dockerfile_parse.parse(f.read())
    if not check(len(stages) >= 2, "Dockerfile: expected a build stage and a runtime stage"):
        return
    build, runtime = stages[0], stages[-1]
    for stage in (build, runtime):
        check(stage.base == "debian:bookworm", f"Dockerfile: stage on {stage.base}, not bookworm")
    build_runs = " ".join(build.all("RUN"))
    check("scripts/install-deps.sh" in build_runs,
          "Dockerfile: the build stage must run scripts/install-deps.sh (the script CI uses)")
    for needle in ("-DCMAKE_BUILD_TYPE=Release", "-DTETREFINE_BUILD_TESTS=OFF",
                   "-DTETREFINE_BUILD_BENCH=OFF", "tetrefine_server", "tetrefine"):
        check(needle in build_runs, f"Dockerfile: the build stage lacks {needle}")
    check(not runtime.all("RUN") or "install-deps.sh" not in " ".join(runtime.all("RUN")),
          "Dockerfile: the runtime stage must not install build dependencies")
    copies = runtime.all("COPY")
    check(copies and all("--from=" in c for c in copies),
          "Dockerfile: the runtime stage copies only built binaries from the build stage")
    user = runtime.last("USER")
    check(user is not None and user.split(":")[0] not in ("0", "root"),
          "Dockerfile: the runtime stage must run as a non-root USER")
    exposed = {int(p.split("/")[0]) for e in runtime.all("EXPOSE") for p in e.split()}
    check(grpc_port in exposed, f"Dockerfile: EXPOSE lacks the gRPC port {grpc_port}")
    check(metrics_port in exposed, f"Dockerfile: EXPOSE lacks the metrics port {metrics_port}")
    check(healthcheck_command(path) == ["tetrefine", "health", "--server", f"127.0.0.1:{grpc_port}"],
          f"Dockerfile: HEALTHCHECK must be CMD tetrefine health --server 127.0.0.1:{grpc_port}")
    entry = dockerfile_parse.exec_form(runtime.last("ENTRYPOINT") or "")
    if check(entry and entry[0] == "tetrefine_server", "Dockerfile: ENTRYPOINT is not the server"):
        listen = [a.split("=", 1)[1] for a in entry if a.startswith("--listen=")]
        check(listen and port_of(listen[0]) == grpc_port,
              f"Dockerfile: ENTRYPOINT --listen must use port {grpc_port}")
        metrics = [a.split("=", 1)[1] for a in entry if a.startswith("--metrics_listen=")]
        check(not metrics or port_of(metrics[0]) == metrics_port,
              f"Dockerfile: ENTRYPOINT --metrics_listen must use port {metrics_port}")


def healthcheck_command(dockerfile):
    """The runtime stage's HEALTHCHECK exec form."""
    with open(dockerfile) as f:
        health = dockerfile_parse.parse(f.read())[-1].last("HEALTHCHECK") or ""
    return dockerfile_parse.exec_form(health.split("CMD", 1)[1].strip()) if "CMD" in health else None


def check_healthcheck_runs(source, server, cli, grpc_port):
    """The HEALTHCHECK command, run with the built CLI against a real server on a free port,
    succeeds; against a stopped server it fails."""
    sys.path.insert(0, os.path.join(source, "tests", "server"))
    from server_process import ServerProcess

    command = healthcheck_command(os.path.join(source, "Dockerfile"))
    if not check(command and command[0] == "tetrefine", "HEALTHCHECK: not a tetrefine command"):
        return

    def run(target):
        args = [cli] + [a.replace(f"127.0.0.1:{grpc_port}", target) for a in command[1:]]
        return subprocess.run(args, capture_output=True, text=True, timeout=60).returncode

    with ServerProcess(server, ["--metrics_listen="]) as live:
        check(run(live.target) == 0, "HEALTHCHECK: fails against a serving server")
        target = live.target
    check(run(target) != 0, "HEALTHCHECK: succeeds with no server")


def labels_match(selector, labels):
    return bool(selector) and all(labels.get(k) == v for k, v in selector.items())


def check_kubernetes(directory, grpc_port, metrics_port):
    documents = []
    for path in sorted(glob.glob(os.path.join(directory, "*.yaml"))):
        with open(path) as f:
            documents += [d for d in yaml.safe_load_all(f) if d]
    by_kind = {}
    for d in documents:
        by_kind.setdefault(d.get("kind"), []).append(d)
    kinds = ("Deployment", "Service", "HorizontalPodAutoscaler", "PodDisruptionBudget")
    present = [check(len(by_kind.get(k, [])) == 1, f"kubernetes: expected one {k}") for k in kinds]
    if not all(present):
        return
    deployment = by_kind["Deployment"][0]
    service = by_kind["Service"][0]
    hpa = by_kind["HorizontalPodAutoscaler"][0]
    pdb = by_kind["PodDisruptionBudget"][0]

    check(deployment["apiVersion"] == "apps/v1", "Deployment: apiVersion apps/v1")
    template = deployment["spec"]["template"]
    pod_labels = template["metadata"]["labels"]
    check(labels_match(deployment["spec"]["selector"]["matchLabels"], pod_labels),
          "Deployment: selector does not match the pod labels")
    annotations = template["metadata"].get("annotations", {})
    check(annotations.get("prometheus.io/scrape") == "true",
          "Deployment: pod annotation prometheus.io/scrape: \"true\"")
    check(str(annotations.get("prometheus.io/port")) == str(metrics_port),
          f"Deployment: pod annotation prometheus.io/port must be {metrics_port}")
    check(annotations.get("prometheus.io/path", "/metrics") == "/metrics",
          "Deployment: prometheus.io/path must be /metrics")
    containers = template["spec"]["containers"]
    check(len(containers) == 1, "Deployment: one container")
    c = containers[0]
    ports = {p["containerPort"] for p in c.get("ports", [])}
    check(grpc_port in ports, f"Deployment: containerPort {grpc_port} missing")
    check(metrics_port in ports, f"Deployment: containerPort {metrics_port} missing")
    resources = c.get("resources", {})
    for kind in ("requests", "limits"):
        for resource in ("cpu", "memory"):
            check(resource in resources.get(kind, {}), f"Deployment: resources.{kind}.{resource}")
    for probe in ("livenessProbe", "readinessProbe"):
        grpc = c.get(probe, {}).get("grpc")
        check(grpc is not None and grpc.get("port") == grpc_port,
              f"Deployment: {probe} must be a native grpc probe on port {grpc_port}")
    check(c.get("readinessProbe", {}).get("grpc", {}).get("service") == "tetrefine.v1.Refiner",
          "Deployment: readiness must ask about tetrefine.v1.Refiner (NOT_SERVING when draining)")
    check(template["spec"].get("securityContext", {}).get("runAsNonRoot") is True,
          "Deployment: runAsNonRoot")
    threads = [a for a in c.get("args", []) if a.startswith("--threads=")]
    check(threads and str(resources.get("limits", {}).get("cpu")) == threads[0].split("=")[1],
          "Deployment: --threads must equal the CPU limit (TBB ignores the CPU quota)")

    check(service["spec"].get("clusterIP") == "None", "Service: must be headless (clusterIP: None)")
    check(labels_match(service["spec"]["selector"], pod_labels),
          "Service: selector does not match the pod labels")
    service_ports = {p["port"]: p for p in service["spec"]["ports"]}
    check(grpc_port in service_ports, f"Service: port {grpc_port} missing")
    named = {p["name"]: p["containerPort"] for p in c.get("ports", [])}
    for p in service["spec"]["ports"]:
        target = p.get("targetPort", p["port"])
        check(named.get(target, target) in ports,
              f"Service: port {p['port']} targets {target}, which the container does not open")

    check(hpa["apiVersion"] == "autoscaling/v2", "HPA: apiVersion must be autoscaling/v2")
    ref = hpa["spec"]["scaleTargetRef"]
    check(ref["kind"] == "Deployment" and ref["name"] == deployment["metadata"]["name"],
          "HPA: scaleTargetRef must name the Deployment")
    check(1 <= hpa["spec"].get("minReplicas", 1) <= hpa["spec"]["maxReplicas"],
          "HPA: minReplicas <= maxReplicas")
    check(hpa["spec"].get("metrics"), "HPA: needs metrics")

    check(pdb["apiVersion"] == "policy/v1", "PDB: apiVersion policy/v1")
    check(labels_match(pdb["spec"]["selector"]["matchLabels"], pod_labels),
          "PDB: selector does not match the pod labels")
    check(("minAvailable" in pdb["spec"]) != ("maxUnavailable" in pdb["spec"]),
          "PDB: exactly one of minAvailable, maxUnavailable")


def check_compose(path, grpc_port):
    with open(path) as f:
        compose = yaml.safe_load(f)
    services = compose.get("services", {})
    check(len(services) >= 2, "compose: expected several replicas")
    host_ports = []
    for name, s in services.items():
        health = s.get("healthcheck", {}).get("test")
        check(health == ["CMD", "tetrefine", "health", "--server", f"127.0.0.1:{grpc_port}"],
              f"compose: {name} needs the tetrefine health healthcheck")
        mapped = [p for p in s.get("ports", []) if str(p).endswith(f":{grpc_port}")]
        check(len(mapped) == 1, f"compose: {name} must publish container port {grpc_port}")
        host_ports += [str(p).rsplit(":", 1)[0] for p in s.get("ports", [])]
    check(len(host_ports) == len(set(host_ports)), "compose: host ports must differ")


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--source", required=True)
    parser.add_argument("--server", required=True)
    parser.add_argument("--cli", help="the built tetrefine CLI: also run the HEALTHCHECK")
    args = parser.parse_args()

    defaults = flag_defaults(args.server)
    if "listen" not in defaults or "metrics_listen" not in defaults:
        sys.exit(f"FAIL: no --listen/--metrics_listen default in {args.server} --helpfull")
    grpc_port, metrics_port = port_of(defaults["listen"]), port_of(defaults["metrics_listen"])
    print(f"server defaults: gRPC port {grpc_port}, metrics port {metrics_port}")

    check_dockerfile(os.path.join(args.source, "Dockerfile"), grpc_port, metrics_port)
    check_kubernetes(os.path.join(args.source, "deploy", "kubernetes"), grpc_port, metrics_port)
    check_compose(os.path.join(args.source, "deploy", "compose.yaml"), grpc_port)
    if args.cli:
        check_healthcheck_runs(args.source, args.server, args.cli, grpc_port)
    for message in failures:
        print("FAIL:", message)
    if not failures:
        print("OK: Dockerfile, deploy/kubernetes and deploy/compose.yaml agree")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
