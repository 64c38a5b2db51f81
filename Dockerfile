# insdiagd on Debian 12, built with the project's own scripts.
#   docker build -t insdiag .      (docker-compose.yml uses it)
# One stage on purpose: the server links Debian's shared gRPC, protobuf,
# libpq, abseil and Ceres's dependency tree, and install-deps.sh is the one
# list of them. Not built by the test suite: the development machines run no
# Docker engine.
FROM debian:12
RUN apt-get update -qq \
    && apt-get install -y -qq --no-install-recommends ca-certificates curl >/dev/null
WORKDIR /src
COPY . .
RUN scripts/install-deps.sh \
    && INSDIAG_BUILD_DIR=/src/build scripts/build.sh -DINSDIAG_BUILD_TESTS=OFF \
    && install -m 0755 build/server/insdiagd build/clients/insdiag /usr/local/bin/ \
    && rm -rf /var/lib/apt/lists/* /src/.cache
EXPOSE 50051 8080
USER nobody
ENTRYPOINT ["/usr/local/bin/insdiagd"]
