#!/usr/bin/env bash
# A throwaway CA and a server certificate for trying TLS locally (deploy/compose.yaml), valid
# for localhost, 127.0.0.1 and the in-cluster names of deploy/kubernetes in NAMESPACE (default:
# default). Production certificates come from your own CA or cert-manager.
#   bash deploy/make-dev-certs.sh DIR [NAMESPACE]
# writes DIR/ca.crt, DIR/ca.key, DIR/tls.crt, DIR/tls.key.
set -euo pipefail
dir="${1:?usage: make-dev-certs.sh DIR [NAMESPACE]}"
namespace="${2:-default}"
mkdir -p "$dir"
cd "$dir"
openssl req -x509 -newkey rsa:2048 -nodes -days 30 -subj "/CN=tetrefine dev CA" \
  -keyout ca.key -out ca.crt 2>/dev/null
openssl req -newkey rsa:2048 -nodes -subj "/CN=tetrefine" -keyout tls.key -out tls.csr 2>/dev/null
cat > tls.ext <<EXT
subjectAltName=DNS:localhost,IP:127.0.0.1,DNS:tetrefine,DNS:tetrefine.${namespace}.svc,DNS:tetrefine.${namespace}.svc.cluster.local
extendedKeyUsage=serverAuth
EXT
openssl x509 -req -in tls.csr -CA ca.crt -CAkey ca.key -CAcreateserial -days 30 \
  -extfile tls.ext -out tls.crt 2>/dev/null
rm -f tls.csr tls.ext ca.srl
# The container runs as uid 10001: a compose secret keeps the file's own mode.
chmod 0644 tls.key
echo "wrote $dir/ca.crt (give it to clients: --tls-ca), $dir/tls.crt and $dir/tls.key"
