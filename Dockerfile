# The repose binary in a small runtime image.
#   docker build -t repose .
FROM rust:1-bookworm AS build
WORKDIR /src
COPY . .
RUN cargo build --release --bin repose

FROM debian:bookworm-slim
RUN apt-get update && apt-get install -y --no-install-recommends ca-certificates && rm -rf /var/lib/apt/lists/*
COPY --from=build /src/target/release/repose /usr/local/bin/repose
COPY --from=build /src/examples /opt/repose/examples
COPY --from=build /src/sweeps /opt/repose/sweeps
WORKDIR /opt/repose
ENTRYPOINT ["repose"]
