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
    # One block per flag: "--name (help...); default: value;" over one or more lines. A help
    # text may wrap onto a line that starts with another flag's name, never with "--name (".
    for block in re.split(r"\n(?=\s*--\w+ \()", text):
        match = re.match(r"\s*--(\w+) .*default: \"?(.*?)\"?;", block, re.S)
        if match:
            defaults[match.group(1)] = match.group(2)
    return defaults


def port_of(address):
    return int(address.rsplit(":", 1)[1])


def memory_bytes(quantity):
    """Kubernetes ("8Gi", "512Mi", "8G") or compose ("4g", "512m") memory quantities, in bytes."""
    text = str(quantity).strip()
    units = {"Ki": 1 << 10, "Mi": 1 << 20, "Gi": 1 << 30, "Ti": 1 << 40,
             "k": 10**3, "M": 10**6, "G": 10**9, "T": 10**12,
             "b": 1, "m": 1 << 20, "g": 1 << 30}
    for suffix in sorted(units, key=len, reverse=True):
        if text.endswith(suffix) and text[:-len(suffix)].replace(".", "", 1).isdigit():
            return int(float(text[:-len(suffix)]) * units[suffix])
    return int(text)


def budget_for_limit(limit):
    """server/memory_budget.cc BudgetForLimit: the limit less max(256 MiB, 10%)."""
    return max(0, limit - max(256 << 20, limit // 10))


def flag_values(args):
    """{name: value} of --name=value arguments."""
    return dict(a[2:].split("=", 1) for a in args if a.startswith("--") and "=" in a)


def check_memory(where, flags, limit, defaults):
    """The refinements a server may run at once, each at its tet budget, fit the budget its
    memory limit gives it (what the server itself enforces per call)."""
    concurrent = int(flags.get("max_concurrent", defaults.get("max_concurrent", 4)))
    tets = int(flags.get("max_output_tets", 0))
    per_tet = int(flags.get("bytes_per_output_tet", defaults.get("bytes_per_output_tet", 160)))
    if not check(tets > 0, f"{where}: set --max_output_tets (the tet budget the memory holds)"):
        return
    budget = budget_for_limit(limit)
    need = concurrent * tets * per_tet
    check(need <= budget,
          f"{where}: {concurrent} refinements of {tets} tets at {per_tet} bytes need {need} bytes, "
          f"more than the budget of {budget} that a {limit}-byte memory limit gives")


def check_tls_args(where, flags, mounted):
    """TLS on by default: a certificate and key under a mounted secret."""
    for flag in ("tls_cert", "tls_key"):
        path = flags.get(flag, "")
        check(path and any(path.startswith(m.rstrip("/") + "/") for m in mounted),
              f"{where}: --{flag} must name a file of the mounted secret ({mounted})")


def entrypoint_local_port(path):
    """The port of the ENTRYPOINT's --local_listen (the probes' plaintext loopback listener)."""
    with open(path) as f:
        runtime = dockerfile_parse.parse(f.read())[-1]
    entry = dockerfile_parse.exec_form(runtime.last("ENTRYPOINT") or "")
    local = [a.split("=", 1)[1] for a in entry if a.startswith("--local_listen=")]
    return port_of(local[0]) if local and local[0].startswith("127.") else None


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
    local_port = entrypoint_local_port(path)
    check(local_port is not None,
          "Dockerfile: ENTRYPOINT needs --local_listen=127.0.0.1:PORT (probes work with TLS on)")
    check(healthcheck_command(path) == ["tetrefine", "health", "--server", f"127.0.0.1:{local_port}"],
          f"Dockerfile: HEALTHCHECK must be CMD tetrefine health --server 127.0.0.1:{local_port}")
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


def check_healthcheck_runs(source, server, cli):
    """With the certificates deploy/make-dev-certs.sh makes, a real server with TLS (as compose
    and Kubernetes run it) answers the HEALTHCHECK command on its plaintext local listener, and a
    TLS client that trusts the dev CA; with the server stopped the HEALTHCHECK fails."""
    sys.path.insert(0, os.path.join(source, "tests", "server"))
    import re
    import tempfile
    from server_process import ServerProcess

    dockerfile = os.path.join(source, "Dockerfile")
    command = healthcheck_command(dockerfile)
    local_port = entrypoint_local_port(dockerfile)
    if not check(command and command[0] == "tetrefine" and local_port,
                 "HEALTHCHECK: not a tetrefine command on the local listener"):
        return

    def run(args):
        return subprocess.run(args, capture_output=True, text=True, timeout=60).returncode

    with tempfile.TemporaryDirectory() as tls:
        made = subprocess.run(["bash", os.path.join(source, "deploy", "make-dev-certs.sh"), tls],
                              capture_output=True, text=True, timeout=60)
        if not check(made.returncode == 0, f"make-dev-certs.sh failed: {made.stderr}"):
            return
        flags = ["--metrics_listen=", "--local_listen=127.0.0.1:0",
                 f"--tls_cert={tls}/tls.crt", f"--tls_key={tls}/tls.key"]
        with ServerProcess(server, flags) as live:
            local = None
            for line in live.log:
                match = re.search(r"plaintext local listener on (127\.0\.0\.1:\d+)", line)
                local = match.group(1) if match else local
            if not check(local, "server: no plaintext local listener logged"):
                return
            healthcheck = [cli] + [a.replace(f"127.0.0.1:{local_port}", local) for a in command[1:]]
            check(run(healthcheck) == 0, "HEALTHCHECK: fails against a serving TLS server")
            # A generous --timeout: under the sanitizers the TLS handshake alone can take more
            # than the default 3 s on a loaded 2-core machine (CI saw it fail there).
            check(run([cli, "health", "--server", f"localhost:{live.port}", "--timeout", "30",
                       "--tls-ca", f"{tls}/ca.crt"]) == 0,
                  "a TLS client trusting the dev CA cannot reach the server")
            check(run([cli, "health", "--server", f"localhost:{live.port}", "--timeout", "30"])
                  != 0, "the TLS port answers plaintext")
        check(run(healthcheck) != 0, "HEALTHCHECK: succeeds with no server")


def labels_match(selector, labels):
    return bool(selector) and all(labels.get(k) == v for k, v in selector.items())


def check_kubernetes(directory, grpc_port, metrics_port, local_port, defaults):
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
    check(annotations.get("prometheus.io/scheme") == "https",
          "Deployment: prometheus.io/scheme must be https (metrics use the gRPC certificate)")
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
    # The kubelet's native gRPC probe cannot speak TLS: probes run the CLI against the
    # entrypoint's plaintext loopback listener.
    health = ["tetrefine", "health", "--server", f"127.0.0.1:{local_port}"]
    for probe in ("startupProbe", "livenessProbe", "readinessProbe"):
        command = c.get(probe, {}).get("exec", {}).get("command", [])
        check(command[:4] == health,
              f"Deployment: {probe} must exec {' '.join(health)} (the local listener)")
    check(c.get("readinessProbe", {}).get("exec", {}).get("command", [])[4:] ==
          ["--service", "tetrefine.v1.Refiner"],
          "Deployment: readiness must ask about tetrefine.v1.Refiner (NOT_SERVING when draining)")
    flags = flag_values(c.get("args", []))
    mounts = [m["mountPath"] for m in c.get("volumeMounts", [])
              if any(v.get("name") == m["name"] and "secret" in v
                     for v in template["spec"].get("volumes", []))]
    check_tls_args("Deployment", flags, mounts)
    # The memory limit reaches the server through the downward API, so its budget follows it.
    env = {e["name"]: e for e in c.get("env", [])}
    limit_flag = flags.get("memory_limit_bytes", "")
    variable = limit_flag[2:-1] if limit_flag.startswith("$(") else None
    field = env.get(variable, {}).get("valueFrom", {}).get("resourceFieldRef", {})
    check(variable and field.get("resource") == "limits.memory",
          "Deployment: --memory_limit_bytes must be $(VAR) with VAR from resourceFieldRef "
          "limits.memory")
    if "memory" in resources.get("limits", {}):
        check_memory("Deployment", flags, memory_bytes(resources["limits"]["memory"]), defaults)
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


def check_compose(path, grpc_port, local_port, defaults):
    with open(path) as f:
        compose = yaml.safe_load(f)
    services = compose.get("services", {})
    check(len(services) >= 2, "compose: expected several replicas")
    secrets = compose.get("secrets", {})
    host_ports = []
    for name, s in services.items():
        health = s.get("healthcheck", {}).get("test")
        check(health == ["CMD", "tetrefine", "health", "--server", f"127.0.0.1:{local_port}"],
              f"compose: {name} needs the tetrefine health healthcheck on the local listener")
        flags = flag_values(s.get("command", []))
        check_tls_args(f"compose: {name}", flags, ["/run/secrets"])
        for flag in ("tls_cert", "tls_key"):
            secret = flags.get(flag, "").rsplit("/", 1)[-1]
            check(secret in s.get("secrets", []) and secret in secrets,
                  f"compose: {name} --{flag} must be one of its secrets")
        if check("mem_limit" in s, f"compose: {name} needs a mem_limit (the server's budget)"):
            check_memory(f"compose: {name}", flags, memory_bytes(s["mem_limit"]), defaults)
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
    local_port = entrypoint_local_port(os.path.join(args.source, "Dockerfile"))
    check_kubernetes(os.path.join(args.source, "deploy", "kubernetes"), grpc_port, metrics_port,
                     local_port, defaults)
    check_compose(os.path.join(args.source, "deploy", "compose.yaml"), grpc_port, local_port,
                  defaults)
    if args.cli:
        check_healthcheck_runs(args.source, args.server, args.cli)
    for message in failures:
        print("FAIL:", message)
    if not failures:
        print("OK: Dockerfile, deploy/kubernetes and deploy/compose.yaml agree")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
