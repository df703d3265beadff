"""The district-heating pipe with plug flow (pipe.py): the district's grid is made of it
(district/grid.py) and the diagnosis replays it (plant/diagnose/pipe_line.py, pipe_recording.py)."""
