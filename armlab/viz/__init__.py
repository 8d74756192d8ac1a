"""Figures and Rerun recordings: the only package that imports matplotlib or rerun.

``armlab.viz.figures`` imports matplotlib when imported; ``armlab.viz.recording`` imports rerun
only inside its functions.
"""

from armlab.viz._paths import preload_rerun
from armlab.viz.cart_diagnosis import (
    cart_diagnosis_figures,
    cart_diagnosis_recording,
)
from armlab.viz.cartesian import (
    format_cartesian_table,
    plot_cartesian_figures,
)
from armlab.viz.cartesian_recording import write_cartesian_recording
from armlab.viz.ci_sweep import plot_ci_window_sweep
from armlab.viz.cond_diagnosis import (
    cond_diagnosis_figures,
    cond_diagnosis_recording,
)
from armlab.viz.diagnosis import (
    diagnosis_figures,
    diagnosis_recording,
)
from armlab.viz.excitation import plot_excitation_comparison
from armlab.viz.figures import (
    plot_error_vs_window,
    plot_validation,
    plot_window_sweep,
)
from armlab.viz.fractional import (
    plot_bode_fits,
    plot_bode_literature,
    plot_time_overlay,
)
from armlab.viz.fractional_recording import FRACTIONAL_SCALAR_CHANNELS, write_fractional_recording
from armlab.viz.fractional_table import format_fractional_table
from armlab.viz.joint import plot_joint_bode
from armlab.viz.recording import (
    DEFAULT_SCALAR_CHANNELS,
    view_command,
    write_recording,
)
from armlab.viz.stiff5_diagnosis import (
    stiff5_diagnosis_figures,
    stiff5_diagnosis_recording,
)
from armlab.viz.stiffness5 import format_stiffness5_table, plot_stiffness5_figures
from armlab.viz.stiffness5_recording import write_stiffness5_recording
from armlab.viz.vfs import format_vfs_tables, plot_vfs_figures, write_vfs_recording

__all__ = [
    "DEFAULT_SCALAR_CHANNELS",
    "plot_ci_window_sweep",
    "plot_excitation_comparison",
    "preload_rerun",
    "plot_error_vs_window",
    "plot_validation",
    "plot_window_sweep",
    "view_command",
    "write_recording",
    "FRACTIONAL_SCALAR_CHANNELS",
    "format_fractional_table",
    "plot_bode_fits",
    "plot_bode_literature",
    "plot_time_overlay",
    "write_fractional_recording",
    "plot_joint_bode",
    "format_vfs_tables",
    "plot_vfs_figures",
    "write_vfs_recording",
    "format_cartesian_table",
    "plot_cartesian_figures",
    "write_cartesian_recording",
    "cart_diagnosis_figures",
    "stiff5_diagnosis_figures",
    "stiff5_diagnosis_recording",
    "cart_diagnosis_recording",
    "cond_diagnosis_figures",
    "cond_diagnosis_recording",
    "diagnosis_figures",
    "diagnosis_recording",
    "format_stiffness5_table",
    "plot_stiffness5_figures",
    "write_stiffness5_recording",
]
