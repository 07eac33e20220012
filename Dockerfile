# Scene (viser, port 8080) and HTTP API (FastAPI, port 8000) in one process, as the README documents:
#   docker build -t ellipsoids . && docker run --rm -p 8080:8080 -p 8000:8000 ellipsoids
#
# Three stages:
#   deps    the runtime dependencies of pyproject.toml in a virtualenv, in a layer of their own
#           (it depends on pyproject.toml alone: a code change does not reinstall them);
#           Playwright is left out (screenshots are a command-line tool, not served by the image)
#   build   the C compiler, and the package built into a wheel (with the landing page, app/static): the compiled float filter
#           (setup.py: core.fixed._filter, baseline / AVX2 / AVX-512 variants chosen when it is
#           imported, so the image runs on any x86-64 CPU; a portable build elsewhere) and the
#           sweep filter of moving bodies (core.moving._sweep_filter)
#   runtime python:3.11-slim, the dependencies' virtualenv, the wheel installed without its
#           dependencies; no compiler, no build tools, no Playwright; a non-root user
FROM python:3.11-slim AS deps

ENV PIP_NO_CACHE_DIR=1 \
    PIP_DISABLE_PIP_VERSION_CHECK=1

WORKDIR /src
COPY pyproject.toml ./
RUN python -m venv /opt/venv \
    && python -c "import tomllib; deps = tomllib.load(open('pyproject.toml', 'rb'))['project']['dependencies']; print('\n'.join(d for d in deps if not d.startswith('playwright')))" > /tmp/requirements.txt \
    && /opt/venv/bin/pip install -r /tmp/requirements.txt


FROM python:3.11-slim AS build

ENV PIP_NO_CACHE_DIR=1 \
    PIP_DISABLE_PIP_VERSION_CHECK=1

# the compiler exists in this stage only
RUN apt-get update && apt-get install -y --no-install-recommends gcc libc6-dev \
    && rm -rf /var/lib/apt/lists/*

WORKDIR /src
COPY pyproject.toml setup.py MANIFEST.in README.md LICENSE ./
COPY core ./core
COPY app ./app
# the landing page: setup.py copies it into the wheel (app/static)
COPY static ./static
# a wheel with the compiled extension (setuptools from the build-system requirements)
RUN pip wheel --no-deps --wheel-dir /wheels . \
    && python -m zipfile -l /wheels/*.whl | grep -q "core/fixed/_filter.*\.so" \
    || (echo "the compiled float filter was not built" >&2 && exit 1)


FROM python:3.11-slim AS runtime

ENV PYTHONDONTWRITEBYTECODE=1 \
    PYTHONUNBUFFERED=1 \
    PIP_NO_CACHE_DIR=1 \
    PIP_DISABLE_PIP_VERSION_CHECK=1 \
    PATH=/opt/venv/bin:$PATH

WORKDIR /srv/ellipsoids

# dependencies first (cached unless pyproject.toml changes), then the package (small layer)
COPY --from=deps /opt/venv /opt/venv
COPY --from=build /wheels /wheels
RUN pip install --no-deps /wheels/*.whl \
    && rm -rf /wheels \
    && python -c "from core.fixed import compiled; assert compiled.available(), compiled.status(); print(compiled.status())" \
    && python -c "from core.moving import sweep_filter as s; assert s.available(), s.filter_status(); print(s.filter_status())" \
    && useradd --create-home --uid 10001 --shell /usr/sbin/nologin app

USER app

EXPOSE 8080 8000

HEALTHCHECK --interval=30s --timeout=5s --start-period=20s --retries=3 \
    CMD ["python", "-c", "import urllib.request; urllib.request.urlopen('http://127.0.0.1:8000/healthz', timeout=4)"]

CMD ["python", "-m", "app", "serve", "--host", "0.0.0.0", "--port", "8080", "--api-port", "8000"]
