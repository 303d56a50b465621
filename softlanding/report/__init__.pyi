"""Type stub of the front door: the names it loads on first use (lazy_loader reads it)."""

from .registry import Context, Section, Settings
from .reproduction import SECTIONS, reproduce, summary_markdown
