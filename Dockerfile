# Scene (viser, port 8080) and HTTP API (FastAPI, port 8000) in one process, as the README documents:
#   docker build -t ellipsoids . && docker run --rm -p 8080:8080 -p 8000:8000 ellipsoids
# Runtime dependencies only (`pip install .`, no test extras, no browser); runs as a non-root user.
FROM python:3.11-slim

ENV PYTHONDONTWRITEBYTECODE=1 \
    PYTHONUNBUFFERED=1 \
    PIP_NO_CACHE_DIR=1 \
    PIP_DISABLE_PIP_VERSION_CHECK=1

WORKDIR /srv/ellipsoids

# A C compiler: the certified float filter (core/fixed/_kernels.c) is compiled on first use for the
# CPU it runs on (-march=native), cached in the user's ~/.cache; without it numpy serves, slower.
RUN apt-get update && apt-get install -y --no-install-recommends gcc libc6-dev \
    && rm -rf /var/lib/apt/lists/*

# Dependencies and packages first (cached unless the code changes).
COPY pyproject.toml README.md ./
COPY core ./core
COPY app ./app
RUN pip install . \
    && useradd --create-home --uid 10001 --shell /usr/sbin/nologin app

# The landing page (served at / by the API; found as ./static from this work directory).
COPY static ./static

USER app

EXPOSE 8080 8000

HEALTHCHECK --interval=30s --timeout=5s --start-period=20s --retries=3 \
    CMD ["python", "-c", "import urllib.request; urllib.request.urlopen('http://127.0.0.1:8000/healthz', timeout=4)"]

CMD ["python", "-m", "app", "serve", "--host", "0.0.0.0", "--port", "8080", "--api-port", "8000"]
