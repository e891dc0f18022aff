# thermogel planner service: FastAPI under uvicorn on the embedded SQLite validation cache.
#   docker build -t thermogel .
#   docker run -p 8000:8000 -v thermogel-data:/data -e THERMOGEL_API_TOKEN=<secret> thermogel
# It binds 0.0.0.0, so it needs an API token (clients send 'Authorization: Bearer <secret>';
# /health stays open for the health check); THERMOGEL_ALLOWED_HOSTS limits the Host names.
FROM python:3.11-slim

ENV PYTHONDONTWRITEBYTECODE=1 \
    PYTHONUNBUFFERED=1 \
    PIP_NO_CACHE_DIR=1 \
    PIP_DISABLE_PIP_VERSION_CHECK=1 \
    NUMBA_CACHE_DIR=/home/app/.cache/numba \
    THERMOGEL_CACHE=/data/cache.sqlite

RUN useradd --create-home --uid 10001 --shell /usr/sbin/nologin app \
    && mkdir -p /data \
    && chown app:app /data

WORKDIR /opt/thermogel
COPY pyproject.toml README.md ./
COPY solver ./solver
COPY dosing ./dosing
COPY api ./api
RUN pip install '.[api]'

USER app
# Compile every numba kernel once into NUMBA_CACHE_DIR, so no container start (and no
# request) pays a compile.
RUN thermogel serve --warmup-only

VOLUME ["/data"]
EXPOSE 8000
HEALTHCHECK --interval=30s --timeout=5s --start-period=60s --retries=3 \
    CMD ["python", "-c", "import sys, urllib.request; r = urllib.request.urlopen('http://127.0.0.1:8000/health', timeout=4); sys.exit(0 if r.status == 200 else 1)"]
CMD ["thermogel", "serve", "--host", "0.0.0.0", "--port", "8000", "--cache", "/data/cache.sqlite"]
