"""Output: ParaView time series, history CSV, pictures, progress bar."""

from masonry_fdem.io.anchor_output import AnchorOutput
from masonry_fdem.io.disk_output import DiskOutput
from masonry_fdem.io.history import History
from masonry_fdem.io.plot import plot_blocks
from masonry_fdem.io.progress import ProgressBar
from masonry_fdem.io.vtx import VTXOutput

__all__ = ["AnchorOutput", "DiskOutput", "History", "ProgressBar", "VTXOutput", "plot_blocks"]
