# PostgreSQL 15 from Debian's packages on the base image made from Debian's
# packages (scripts/container-base-image.sh); built by
# scripts/container-images.sh. The entrypoint mirrors the official image's
# variables: POSTGRES_USER (the cluster's superuser), POSTGRES_PASSWORD,
# POSTGRES_DB, plus PGPORT and POSTGRES_LISTEN (default 127.0.0.1).
ARG BASE_IMAGE=insdiag-base:bookworm
FROM ${BASE_IMAGE}
# No cluster made by the package, no service started at install.
RUN printf '#!/bin/sh\nexit 101\n' >/usr/sbin/policy-rc.d && chmod 0755 /usr/sbin/policy-rc.d \
    && mkdir -p /etc/postgresql-common/createcluster.d \
    && echo 'create_main_cluster = false' >/etc/postgresql-common/createcluster.d/insdiag.conf \
    && apt-get update -qq \
    && DEBIAN_FRONTEND=noninteractive apt-get -y -qq upgrade >/dev/null \
    && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq postgresql-15 >/dev/null \
    && rm -rf /var/lib/apt/lists/* \
    && install -d -o postgres -g postgres -m 0700 /var/lib/postgresql/data \
    && install -d -o postgres -g postgres -m 2775 /var/run/postgresql
COPY postgres-entrypoint.sh /usr/local/bin/
ENV PATH=/usr/lib/postgresql/15/bin:$PATH PGDATA=/var/lib/postgresql/data
USER postgres
VOLUME /var/lib/postgresql/data
# SIGINT is PostgreSQL's fast shutdown: sessions are ended, the stop is clean.
STOPSIGNAL SIGINT
ENTRYPOINT ["/usr/local/bin/postgres-entrypoint.sh"]
