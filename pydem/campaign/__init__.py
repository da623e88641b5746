"""Simulation campaigns: a rig, parameter ranges, a space-filling design and one resumable HDF5
store (DESIGN section 7). `Campaign` runs it locally (process pool) or on a Dask cluster."""
from .design import design_points
from .runner import Campaign, simulate
from .spec import CampaignSpec, SpecError
from .store import CampaignStore, StoreError

__all__ = ["Campaign", "CampaignSpec", "CampaignStore", "SpecError", "StoreError", "design_points", "simulate"]
