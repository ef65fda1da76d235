#!/usr/bin/env python3
"""Checks the deployment files that no test runs for real here (no cluster): docs/scaling.md.

usage: python3 tests/deploy/manifests_check.py      (from the repository root)

- every YAML document of deploy/k8s/*.yaml and docker/compose.scale.yaml parses, and the
  Kubernetes ones have apiVersion, kind and metadata.name (the kustomization: its resources exist)
- the ConfigMap's haproxy.cfg in deploy/k8s/haproxy.yaml is deploy/haproxy/haproxy.cfg, byte
  for byte (it is a copy: kubectl cannot include a file from outside the kustomization)
- `haproxy -c` accepts haproxy.cfg with each deployment's backend (compose, Kubernetes)

Exits 77 (ctest: skipped) when PyYAML is missing; `haproxy -c` is skipped, with a note, when
haproxy is missing. Exits 1 at the first failure.
"""
import glob
import os
import shutil
import subprocess
import sys
import tempfile

try:
    import yaml
except ImportError:
    print("SKIPPED: no PyYAML (Debian's python3-yaml; tools/setup.sh installs it)")
    sys.exit(77)

HAPROXY_CFG = "deploy/haproxy/haproxy.cfg"


def fail(msg):
    print(f"manifests: FAIL {msg}")
    sys.exit(1)


def load_all(path):
    try:
        with open(path) as f:
            return [d for d in yaml.safe_load_all(f) if d is not None]
    except yaml.YAMLError as e:
        fail(f"{path} does not parse: {e}")


def check_k8s():
    configmap = None
    for path in sorted(glob.glob("deploy/k8s/*.yaml")):
        docs = load_all(path)
        for doc in docs:
            if doc.get("kind") == "Kustomization":
                for res in doc.get("resources", []):
                    if not os.path.exists(os.path.join("deploy/k8s", res)):
                        fail(f"{path}: resource {res} does not exist")
                continue
            for key in ("apiVersion", "kind"):
                if key not in doc:
                    fail(f"{path}: a document has no {key}")
            if not doc.get("metadata", {}).get("name"):
                fail(f"{path}: a {doc['kind']} has no metadata.name")
            if doc["kind"] == "ConfigMap" and doc["metadata"]["name"] == "tumble-haproxy":
                configmap = doc
        print(f"manifests: ok   {path}: {', '.join(d['kind'] for d in docs)}")
    if configmap is None:
        fail("no ConfigMap tumble-haproxy in deploy/k8s")
    with open(HAPROXY_CFG) as f:
        if configmap["data"].get("haproxy.cfg") != f.read():
            fail(f"the ConfigMap's haproxy.cfg differs from {HAPROXY_CFG}: copy the file into it")
    print(f"manifests: ok   the ConfigMap's haproxy.cfg is {HAPROXY_CFG}")
    return configmap["data"]["backend.cfg"]


def check_compose():
    path = "docker/compose.scale.yaml"
    doc = load_all(path)[0]
    for service in ("tumble", "haproxy"):
        if service not in doc.get("services", {}):
            fail(f"{path} has no service {service}")
    print(f"manifests: ok   {path}: services {', '.join(doc['services'])}")


def haproxy_check(k8s_backend):
    haproxy = shutil.which("haproxy") or shutil.which("haproxy", path="/usr/sbin:/usr/local/sbin")
    if not haproxy:
        print("manifests: note haproxy not installed: configs not checked with haproxy -c")
        return
    env = dict(os.environ, POD_NAMESPACE="default", CLUSTER_DOMAIN="cluster.local")
    with tempfile.NamedTemporaryFile("w", suffix=".cfg") as k8s:
        k8s.write(k8s_backend)
        k8s.flush()
        for name, backend in (("compose", "deploy/haproxy/backend.compose.cfg"), ("k8s", k8s.name)):
            r = subprocess.run([haproxy, "-c", "-f", HAPROXY_CFG, "-f", backend], env=env,
                               capture_output=True, text=True, timeout=20)
            if r.returncode != 0:
                fail(f"haproxy -c with the {name} backend:\n{r.stdout}{r.stderr}")
            print(f"manifests: ok   haproxy -c accepts haproxy.cfg + the {name} backend")


def main():
    k8s_backend = check_k8s()
    check_compose()
    haproxy_check(k8s_backend)


if __name__ == "__main__":
    main()
