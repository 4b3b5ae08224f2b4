"""The leaderboard pages of the documentation site, made from the committed boards under
``leaderboards/`` alone: :mod:`.catalogue` what no CSV says (the study, the paper, the sensor),
:mod:`.boards` the committed files as read, :mod:`.html` the sortable tables, :mod:`.plots` a
board's methods against its limits, :mod:`.verdicts` and :mod:`.summary` what the pages conclude,
:mod:`.render` the pages, :mod:`.output` writing them, :mod:`.command` ``tcbench pages``.

Nothing is imported here: import the submodules.
"""
