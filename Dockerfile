# Multi-stage build of the gangue service: compile the release binary, run it as a non-root user.
FROM rust:1.95-bookworm AS build
WORKDIR /src
COPY Cargo.toml Cargo.lock build.rs ./
COPY src ./src
COPY static ./static
COPY benches ./benches
# The commit built (docker build --build-arg GANGUE_GIT_HASH=$(git rev-parse HEAD)); without it
# the build id of sharded computations is a hash of the binary.
ARG GANGUE_GIT_HASH=
ENV GANGUE_GIT_HASH=${GANGUE_GIT_HASH}
RUN cargo build --release --locked --bin gangue

FROM debian:bookworm-slim AS runtime
RUN useradd --system --uid 10001 --no-create-home --shell /usr/sbin/nologin gangue
COPY --from=build /src/target/release/gangue /usr/local/bin/gangue
USER gangue
ENV GANGUE_BIND=0.0.0.0:8080
EXPOSE 8080
ENTRYPOINT ["/usr/local/bin/gangue"]
