"""The juggling task of Lippi, Avizzano & Ruffaldi (section III-A): data layer.

The public names of small private modules, one concern each:

* ``_task``: every constant (:class:`JugglingTask`), the world's state
  (:class:`JugglingState`), a run's perturbations (:class:`JugglingNoise`), the phases
  (:data:`PHASES`) and the ballistic closed form;
* :mod:`~motion_envs.datasets.juggling.rules` (public, used as a namespace:
  ``rules.catch_fires(...)``): the world's rules (release, catch, drop, flight), written
  once for one ball and for a batch, used by the pure-model world, the MuJoCo scene, the
  vectorised runner, the demonstration generator and the segmentation;
* ``_records``: recordings, phase examples, demonstration sets and their split; the
  juggling environments' episode seeds per split (:data:`SPLIT_SEEDS`, :func:`episode_seeds`);
* ``_paths``: paths on normalised time (resampling, departure from the line);
* ``_person``: the SIMULATED demonstrations (a seeded model of a person);
* ``_cascade_demos``: SIMULATED three-ball cascade demonstrations (two hands, each in its
  own frame) and the pattern's timing from Shannon's juggling theorem;
* ``_siteswap``: siteswap notation (validity, ball count) and each throw's flight at a
  tempo;
* ``_csv``: the users' juggling CSV, read as raw recordings.
"""

from motion_envs.datasets.juggling import rules
from motion_envs.datasets.juggling._cascade_demos import (
    CASCADE_BALLS,
    CASCADE_HANDS,
    CASCADE_STYLES,
    CascadeStyle,
    CascadeTiming,
    NominalToss,
    cascade_timing,
    draw_cascade_person,
    generate_cascade_demonstrations,
    mirror_x,
    nominal_toss,
    style_timing,
)
from motion_envs.datasets.juggling._csv import (
    JUGGLING_COLUMNS,
    MIN_SAMPLES,
    read_juggling_csv,
    write_juggling_csv,
)
from motion_envs.datasets.juggling._paths import departure_from_line, resample_path
from motion_envs.datasets.juggling._person import (
    PersonStyle,
    draw_person,
    generate_demonstrations,
)
from motion_envs.datasets.juggling._records import (
    MAX_SPLIT_EPISODES,
    MIN_SPLIT_CYCLES,
    SIMULATED_LABEL,
    SPLIT_SEEDS,
    JugglingDemos,
    JugglingRecording,
    PhaseSegment,
    episode_seeds,
    split_cycles,
)
from motion_envs.datasets.juggling._siteswap import (
    MAX_SITESWAP_PERIOD,
    SITESWAP_DIGITS,
    format_siteswap,
    parse_siteswap,
    siteswap_balls,
    siteswap_flights,
)
from motion_envs.datasets.juggling._task import (
    PHASES,
    JugglingNoise,
    JugglingState,
    JugglingTask,
    ballistic_position,
    ballistic_velocity,
)

__all__ = [
    "CASCADE_BALLS",
    "CASCADE_HANDS",
    "CASCADE_STYLES",
    "JUGGLING_COLUMNS",
    "MAX_SITESWAP_PERIOD",
    "MAX_SPLIT_EPISODES",
    "MIN_SAMPLES",
    "MIN_SPLIT_CYCLES",
    "PHASES",
    "SIMULATED_LABEL",
    "SITESWAP_DIGITS",
    "SPLIT_SEEDS",
    "CascadeStyle",
    "CascadeTiming",
    "JugglingDemos",
    "JugglingNoise",
    "JugglingRecording",
    "JugglingState",
    "JugglingTask",
    "NominalToss",
    "PersonStyle",
    "PhaseSegment",
    "ballistic_position",
    "ballistic_velocity",
    "cascade_timing",
    "departure_from_line",
    "draw_cascade_person",
    "draw_person",
    "episode_seeds",
    "format_siteswap",
    "generate_cascade_demonstrations",
    "generate_demonstrations",
    "mirror_x",
    "nominal_toss",
    "parse_siteswap",
    "read_juggling_csv",
    "resample_path",
    "rules",
    "siteswap_balls",
    "siteswap_flights",
    "split_cycles",
    "style_timing",
    "write_juggling_csv",
]
