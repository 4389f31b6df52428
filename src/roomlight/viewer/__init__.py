"""``roomlight view``: an interactive, self-contained HTML page for a 2.5D area light."""

from roomlight.viewer.page import viewer_payload, write_viewer
from roomlight.viewer.three import THREE_VERSION, three_dir

__all__ = ["write_viewer", "viewer_payload", "three_dir", "THREE_VERSION"]
