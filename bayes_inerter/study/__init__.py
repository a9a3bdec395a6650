"""Studies: many records and models at once, their tables, figures and report."""

from .headline import write_headline
from .plan import FitJob, StudyPlan, full_plan, quick_plan
from .run import StudyResult, run_study
from .runner import run_jobs

__all__ = ["FitJob", "StudyPlan", "full_plan", "quick_plan", "StudyResult", "run_study", "run_jobs", "write_headline"]
