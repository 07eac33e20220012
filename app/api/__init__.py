"""HTTP API (FastAPI) over the certified classifier and the motion analyser.

Public API::

    from app.api import create_api, ApiSettings
    app = create_api(ApiSettings(scene_url="http://127.0.0.1:8080"))   # serve with uvicorn
"""

from .factory import create_api as create_api
from .settings import ApiSettings as ApiSettings

__all__ = ["ApiSettings", "create_api"]
