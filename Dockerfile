# tetrefine: the gRPC refinement server and the `tetrefine` CLI on Debian 12.
#
#   docker build -t tetrefine:0.1.0 .
#   docker run --rm -p 50051:50051 -p 9464:9464 tetrefine:0.1.0
#   docker run --rm --entrypoint tetrefine tetrefine:0.1.0 health --server host:50051
#
# Server flags go after the image name (they follow the entrypoint's), e.g. --threads=2, or
# --tls_cert=... --tls_key=... for TLS (deploy/README.md). The HEALTHCHECK asks the plaintext
# listener the entrypoint opens on the container's loopback, so it works with TLS on or off.

# --- build: the same dependency script as CI and the README, a Release build without tests ---
FROM debian:bookworm AS build
WORKDIR /src
COPY scripts/install-deps.sh scripts/install-deps.sh
RUN TETREFINE_WITH_TEST_TOOLS=0 bash scripts/install-deps.sh && rm -rf /var/lib/apt/lists/*
COPY . .
RUN cmake -S . -B /build -G Ninja -DCMAKE_BUILD_TYPE=Release \
      -DTETREFINE_BUILD_TESTS=OFF -DTETREFINE_BUILD_BENCH=OFF -DCMAKE_UNITY_BUILD=ON \
 && cmake --build /build --target tetrefine_server tetrefine \
 && mkdir -p /out \
 && cp /build/server/tetrefine_server /build/client/tetrefine /out/ \
 && strip /out/tetrefine_server /out/tetrefine

# --- runtime: the two binaries and the shared libraries they load, nothing else ---
# (libcairo2 and the libraries from libpixman-1-0 on are for `tetrefine slice`, which draws PNG
# figures with Cairo; Debian's Cairo links X11 even when only image surfaces are used.)
# The package list is checked against `ldd` of the built binaries by
# tests/deploy/check_runtime_packages.py (ctest DockerRuntimePackages).
FROM debian:bookworm
RUN apt-get update \
 && apt-get install -y --no-install-recommends \
      libgrpc++1.51 libgrpc29 libprotobuf32 libabsl20220623 libc-ares2 libre2-9 libssl3 \
      libtbb12 libspdlog1.10 libfmt9 zlib1g libpugixml1v5 liblzma5 liblz4-1 libdeflate0 libisal2 \
      libprometheus-cpp-core1.0 libprometheus-cpp-pull1.0 libcivetweb1 \
      libstdc++6 libgcc-s1 libtcmalloc-minimal4 ca-certificates \
      libcairo2 libpixman-1-0 libfontconfig1 libfreetype6 libpng16-16 libexpat1 libbrotli1 \
      libxcb1 libxcb-render0 libxcb-shm0 libxrender1 libx11-6 libxext6 libxau6 libxdmcp6 \
      libbsd0 libmd0 \
 && rm -rf /var/lib/apt/lists/* \
 && useradd --system --uid 10001 --user-group --no-create-home --shell /usr/sbin/nologin tetrefine
COPY --from=build /out/tetrefine_server /out/tetrefine /usr/local/bin/
USER 10001:10001
# gRPC (tetrefine.v1.Refiner, grpc.health.v1, reflection) and Prometheus /metrics (HTTPS when
# gRPC has TLS). 50052 is the loopback-only plaintext listener for probes inside the container.
EXPOSE 50051 9464
HEALTHCHECK --interval=15s --timeout=5s --start-period=10s --retries=3 \
  CMD ["tetrefine","health","--server","127.0.0.1:50052"]
ENTRYPOINT ["tetrefine_server", "--listen=0.0.0.0:50051", "--metrics_listen=0.0.0.0:9464", \
            "--local_listen=127.0.0.1:50052"]
