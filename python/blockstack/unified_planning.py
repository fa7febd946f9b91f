"""blockstack as a planner of the Unified Planning Framework (UPF).

UPF (``pip install "blockstack[up]"``) runs planners behind one interface; Fast Downward is
one of its defaults. :class:`BlockstackPlanner` makes blockstack one for the Blocks World:
register it once, then ask for it by name::

    from unified_planning.shortcuts import get_environment, OneshotPlanner
    from unified_planning.io import PDDLReader

    get_environment().factory.add_engine("blockstack", "blockstack.unified_planning", "BlockstackPlanner")
    problem = PDDLReader().parse_problem("domain.pddl", "p01.pddl")
    with OneshotPlanner(name="blockstack") as planner:
        result = planner.solve(problem)
    print(result.status, result.plan)

It plans the 4-operator Blocks World (``pickup``/``putdown``/``stack``/``unstack``, or
``pick-up``/``put-down``) and nothing else: the problem is written as PDDL by UPF's own
``PDDLWriter`` and read by blockstack's checked reader (``blockstack solve --pddl P
--domain D`` reads the same files), which accepts the domain only if its actions are the
Blocks World's, precondition and effect alike. Any other problem is answered
``UNSUPPORTED_PROBLEM``, with the reader's reason in the result's log. So the rules live in
one place, the native module; nothing of them is written again here.

The status is ``SOLVED_OPTIMALLY`` when the plan's cost meets the proven lower bound (the
optimal solver's certificate, see ``blockstack.solve_pddl``), ``SOLVED_SATISFICING``
otherwise; the result's ``metrics`` carry the cost, the bound and the solver.
"""

from __future__ import annotations

import os
import tempfile
import warnings
from typing import IO, Callable, Optional

import unified_planning as up
from unified_planning.engines import Credits, Engine, LogLevel, LogMessage, PlanGenerationResult
from unified_planning.engines import PlanGenerationResultStatus as Status
from unified_planning.engines.mixins.oneshot_planner import OneshotPlannerMixin, OptimalityGuarantee
from unified_planning.io import PDDLWriter
from unified_planning.model import ProblemKind
from unified_planning.plans import ActionInstance, SequentialPlan

from blockstack.planning import solve_pddl

__all__ = ["BlockstackPlanner"]

_CREDITS = Credits(
    name="blockstack",
    author="the blockstack authors",
    contact="",
    website="",
    license="MIT OR Apache-2.0",
    short_description="Optimal and near-optimal plans for the 4-operator Blocks World, with a proven lower bound.",
    long_description="blockstack plans the Blocks World by block moves and proves a lower bound on the cost "
    "(misplaced blocks, blocks forced to move twice, and a smallest set of blocks that breaks every deadlock, "
    "after Slaney and Thiebaux, 'Blocks World revisited', AIJ 2001).",
)


class BlockstackPlanner(Engine, OneshotPlannerMixin):
    """A UPF one-shot planner for the 4-operator Blocks World.

    ``solver`` is the planner, as ``blockstack solve --solver`` names it: ``"optimal"`` (the
    default; the fewest moves, with its proof, within ``time_limit`` seconds, else its best
    plan), ``"near-optimal"`` or ``"exact"``. ``solve(problem, timeout=T)`` gives the
    optimal solver ``T`` seconds in place of ``time_limit``.
    """

    def __init__(self, solver: str = "optimal", time_limit: Optional[float] = None, **kwargs):
        Engine.__init__(self)
        OneshotPlannerMixin.__init__(self)
        if not isinstance(solver, str):
            raise TypeError(f"solver is a name (str), not {solver!r}")
        self._solver = solver
        self._time_limit = time_limit

    @property
    def name(self) -> str:
        return "blockstack"

    @staticmethod
    def get_credits(**kwargs) -> Optional[Credits]:
        return _CREDITS

    @staticmethod
    def supported_kind() -> ProblemKind:
        """Classical problems with types, the kind the Blocks World's PDDL is read as; within
        it, only the Blocks World itself is planned (others get ``UNSUPPORTED_PROBLEM``)."""
        kind = ProblemKind(version=2)
        kind.set_problem_class("ACTION_BASED")
        kind.set_typing("FLAT_TYPING")
        kind.set_typing("HIERARCHICAL_TYPING")
        kind.set_quality_metrics("PLAN_LENGTH")
        return kind

    @staticmethod
    def supports(problem_kind: ProblemKind) -> bool:
        return problem_kind <= BlockstackPlanner.supported_kind()

    @staticmethod
    def satisfies(optimality_guarantee: OptimalityGuarantee) -> bool:
        # Optimality is proven per problem (the status says so), not promised for every one.
        return optimality_guarantee == OptimalityGuarantee.SATISFICING

    def _solve(
        self,
        problem: "up.model.AbstractProblem",
        heuristic: Optional[Callable] = None,
        timeout: Optional[float] = None,
        output_stream: Optional[IO[str]] = None,
    ) -> PlanGenerationResult:
        if heuristic is not None:
            warnings.warn("blockstack plans the Blocks World by its own bound: the heuristic is not used")
        time_limit = timeout if timeout is not None else self._time_limit
        if self._solver != "optimal":
            if timeout is not None:
                warnings.warn(f"the timeout is the optimal solver's time limit: solver={self._solver!r} does not use it")
            time_limit = None
        with tempfile.TemporaryDirectory(prefix="blockstack-up-") as folder:
            domain = os.path.join(folder, "domain.pddl")
            task = os.path.join(folder, "problem.pddl")
            try:
                writer = PDDLWriter(problem)
                writer.write_domain(domain)
                writer.write_problem(task)
                solved = solve_pddl(task, solver=self._solver, time_limit=time_limit, domain=domain)
            except (ValueError, up.exceptions.UPException) as refused:
                # Not the Blocks World (the reader says what is not), a state it cannot be,
                # or a problem PDDL cannot write at all.
                return self._unsupported(str(refused).replace(folder + os.sep, ""), output_stream)
        if output_stream is not None:
            output_stream.write(solved["text"])
        plan = SequentialPlan([_action_instance(writer, text) for text in solved["plan"]])
        status = Status.SOLVED_OPTIMALLY if solved["optimal"] else Status.SOLVED_SATISFICING
        metrics = {
            "cost": str(solved["cost"]),
            "lower_bound": str(solved["lower_bound"]),
            "solver": solved["solver"],
        }
        return PlanGenerationResult(status, plan, self.name, metrics=metrics)


    def _unsupported(self, reason: str, output_stream: Optional[IO[str]]) -> PlanGenerationResult:
        """The answer to a problem this engine does not plan, ``reason`` in its log."""
        if output_stream is not None:
            output_stream.write(reason + "\n")
        return PlanGenerationResult(
            Status.UNSUPPORTED_PROBLEM,
            None,
            self.name,
            log_messages=[LogMessage(LogLevel.ERROR, reason)],
        )


def _action_instance(writer: PDDLWriter, text: str) -> ActionInstance:
    """The UPF action of the plan line ``text`` (``"(pick-up b1)"``), its names mapped back
    through the writer that named them."""
    name, *args = text.strip("()").split()
    action = writer.get_item_named(name)
    objects = [writer.get_item_named(arg) for arg in args]
    return ActionInstance(action, tuple(objects))
