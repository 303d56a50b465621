"""Type stub of the front door: the names it loads on first use (lazy_loader reads it)."""

from .registry import Context as Context, Section as Section, Settings as Settings
from .reproduction import SECTIONS as SECTIONS, reproduce as reproduce, summary_markdown as summary_markdown
