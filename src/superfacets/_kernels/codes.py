"""The modes and status codes the expansion kernels share (their callers and the
reference kernels read them here)."""

#: ``mode`` of ``expand``: label faces that get a strictly lower distance
MERGE = 0
#: ``mode`` of ``expand``: enter and label only faces without a label
UNLABELLED = 1
#: ``mode`` of ``expand``: touch neither ``dist`` nor ``label``, only record
RECORD = 2
#: status returned when the visit/record arrays are full
RECORD_FULL = -1
#: status returned when the queue is full
QUEUE_FULL = -2
#: ``reclassify_exact``: no incremental pass possible, nothing changed
NOT_INCREMENTAL = -100
