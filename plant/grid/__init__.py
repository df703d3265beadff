"""The district-heating grid between the houses: plug-flow pipes (pipe.py), the network of nodes
with its plant and the houses' substations (network.py), and the district file (district.py)."""
