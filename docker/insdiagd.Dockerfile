# insdiagd and the insdiag CLI from a Debian 12 build of the project
# (scripts/build.sh), on the base image made from Debian's packages
# (scripts/container-base-image.sh). Built by scripts/container-images.sh,
# which stages the binaries, the page and this file as the build context and
# passes RUNTIME_PACKAGES: the Debian packages of the shared libraries the
# binaries load (ldd), so only the runtime libraries are installed — no
# compiler, no -dev package, no PostgreSQL server.
ARG BASE_IMAGE=insdiag-base:bookworm
FROM ${BASE_IMAGE}
ARG RUNTIME_PACKAGES
RUN test -n "$RUNTIME_PACKAGES" \
    && apt-get update -qq \
    && DEBIAN_FRONTEND=noninteractive apt-get -y -qq upgrade >/dev/null \
    && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq $RUNTIME_PACKAGES >/dev/null \
    && rm -rf /var/lib/apt/lists/* \
    && useradd --system --home-dir /var/lib/insdiag --shell /usr/sbin/nologin insdiag \
    && install -d -o insdiag -g insdiag -m 0700 /var/lib/insdiag
COPY insdiagd insdiag insdiag-healthz /usr/local/bin/
COPY web /usr/share/insdiag/web
# A library the package list missed fails the build here, not at start.
RUN if ldd /usr/local/bin/insdiagd /usr/local/bin/insdiag | grep 'not found'; then \
      echo 'insdiagd image: shared libraries missing (were the binaries built on Debian 12?)' >&2; exit 1; fi
# The first admin token is written to INSDIAG_DATA_DIR/admin-token; the
# database is always external (--database-url / INSDIAG_DATABASE_URL).
ENV INSDIAG_DATA_DIR=/var/lib/insdiag INSDIAG_WEB_DIR=/usr/share/insdiag/web
USER insdiag
WORKDIR /var/lib/insdiag
VOLUME /var/lib/insdiag
ENTRYPOINT ["/usr/local/bin/insdiagd"]
CMD ["--bind=127.0.0.1"]
