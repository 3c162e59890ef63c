"""Benchmark: the ConceptBot paper's 47 tasks, with gold acceptance criteria and automatic grading.

The tasks live in ``conceptbot/bench/tasks/<category>.json`` (one file per category of the paper's
appendix: unambiguous, ambiguous, implicit, risk, materials, toxic), each a list of tasks with the paper's
request, the demo scene it runs in (:mod:`conceptbot.scenes`), a gold acceptance criterion, and notes that
record every judgement call made in writing that criterion. :mod:`conceptbot.bench.grading` loads and
validates them and grades a plan against a task, returning a verdict with a reason.

Example::

    from conceptbot.bench.grading import grade, load_tasks
    from conceptbot.core.plan import Done, PickAndPlace

    task = next(t for t in load_tasks(["ambiguous"]) if t.id == "ambiguous-2")
    grade(task, [PickAndPlace("apple", "user"), Done()])    # Verdict(ok=True, ...)
"""
