"""The district: houses on a district-heating grid. The district file and its loader
(declaration.py, the shipped files in districts/), the grid of nodes and plug-flow pipes
(grid.py; the pipe itself is the plant's, plant/grid/pipe.py) and the co-simulation of the
houses and the grid, one process each (federation/)."""
