"""The local web page (``conceptbot serve``): ask, watch the reasoning stream in, see the plan executed."""
