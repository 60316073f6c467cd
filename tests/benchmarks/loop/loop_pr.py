#!/usr/bin/env python3
"""Loop-detection precision/recall of a keygrid-slam run against ground truth.

  loop_pr.py score --run DIR --gt GT.txt [--name S] [--mode M] [--json OUT.json]
  loop_pr.py table A.json B.json ...          (markdown tables of several scores)

Inputs of `score`: keygrid-slam's output folder (report.json: `loop_closures` with `frame`,
`keyframe`, `loop_keyframe`; frames.csv: one row per frame with its timestamp and whether it
created a keyframe) and a TUM ground truth (nearest timestamp within 20 ms).

Keyframe ids are SparseMap's counter (0, 1, 2, ... in creation order, culled ids are not
reused), so the n-th frame with new_keyframe = 1 created keyframe n. The query side of a loop
event is checked against that (`keyframe` must be the keyframe created at `frame`).

Definitions (doc/loop-closure.md):
* GT revisit of frame i: an earlier frame j with |c_i - c_j| <= 0.5 m, angle between the optical
  axes <= 30 deg, t_i - t_j >= 10 s and GT path length from j to i >= 2 m.
* Revisit event: a maximal run of consecutive frames with a GT revisit.
* A detected loop (query frame, frame of its loop keyframe) is a true positive when their GT
  poses are within 1 m and 45 deg, else a false positive.
* Independently of TP/false, a detection's constraint is **correct** when the relative pose
  that geometric verification measured agrees with ground truth: camera distance within
  CONSTRAINT_DIST_M and relative rotation angle within CONSTRAINT_ANGLE_DEG
  (report.json `measured_distance_m`, `measured_angle_deg`). A wrong constraint is what corrupts
  a pose graph; a correct one between cameras farther apart than TP_DIST_M (two views of the
  same wall from 2.5 m apart) is a false positive of place recognition but not a false loop.
* Precision = TP / detections; recall = events with a TP detection inside [start - 1 s, end + 1 s]
  / events ("strict": inside [start, end + 1 s]; a TP detection can precede the event because the
  TP radius, 1 m, is larger than the revisit radius, 0.5 m).
"""
import argparse
import csv
import json
import math
import os
import sys

import numpy as np

REVISIT_DIST_M = 0.5
REVISIT_ANGLE_DEG = 30.0
REVISIT_MIN_DT_S = 10.0
REVISIT_MIN_PATH_M = 2.0
TP_DIST_M = 1.0
TP_ANGLE_DEG = 45.0
EVENT_GRACE_S = 1.0
CONSTRAINT_DIST_M = 0.10
CONSTRAINT_ANGLE_DEG = 5.0
ASSOC_MAX_DT_S = 0.02


def read_tum(path, with_quaternions=False):
	"""TUM trajectory -> (timestamps [N], centres [N, 3], optical axes [N, 3]) and, when asked,
	the unit quaternions [N, 4] (x, y, z, w)."""
	rows = []
	with open(path) as f:
		for line in f:
			line = line.strip()
			if not line or line.startswith('#'):
				continue
			v = [float(x) for x in line.split()[:8]]
			rows.append(v)
	a = np.array(rows, dtype=float)
	t, p, q = a[:, 0], a[:, 1:4], a[:, 4:8]
	q = q / np.linalg.norm(q, axis=1, keepdims=True)
	x, y, z, w = q[:, 0], q[:, 1], q[:, 2], q[:, 3]
	# Third column of the rotation matrix: the camera's optical (z) axis in the world.
	axis = np.stack([2 * (x * z + w * y), 2 * (y * z - w * x), 1 - 2 * (x * x + y * y)], axis=1)
	if with_quaternions:
		return t, p, axis, q
	return t, p, axis


def rotation_angle_deg(qa, qb):
	"""Angle of the relative rotation between two unit quaternions."""
	return float(np.degrees(2 * np.arccos(min(1.0, abs(float(np.dot(qa, qb)))))))


def read_frames(run):
	"""frames.csv -> (timestamps [N], keyframe id created at each frame or -1)."""
	ts, kf = [], []
	next_id = 0
	with open(os.path.join(run, 'frames.csv')) as f:
		for r in csv.DictReader(f):
			if int(r['index']) != len(ts):
				raise ValueError('frames.csv: index %s at row %d' % (r['index'], len(ts)))
			ts.append(float(r['timestamp']))
			if int(r['new_keyframe']):
				kf.append(next_id)
				next_id += 1
			else:
				kf.append(-1)
	return np.array(ts), np.array(kf)


def associate(frame_t, gt_t):
	"""Index of the nearest GT sample per frame, -1 when farther than ASSOC_MAX_DT_S."""
	order = np.argsort(gt_t)
	gs = gt_t[order]
	k = np.clip(np.searchsorted(gs, frame_t), 1, len(gs) - 1)
	left, right = gs[k - 1], gs[k]
	pick = np.where(np.abs(frame_t - left) <= np.abs(frame_t - right), k - 1, k)
	idx = order[pick]
	idx[np.abs(gt_t[idx] - frame_t) > ASSOC_MAX_DT_S] = -1
	return idx


def angle_deg(a, b):
	c = np.clip(np.sum(a * b, axis=-1), -1.0, 1.0)
	return np.degrees(np.arccos(c))


def revisits(t, c, ax):
	"""Boolean per frame: has a GT revisit (definition above); and the best earlier frame."""
	n = len(t)
	step = np.r_[0.0, np.linalg.norm(np.diff(c, axis=0), axis=1)]
	s = np.cumsum(step)  # GT path length from frame 0
	has = np.zeros(n, dtype=bool)
	best = np.full(n, -1)
	for i in range(n):
		j = np.nonzero((t[i] - t[:i] >= REVISIT_MIN_DT_S) & (s[i] - s[:i] >= REVISIT_MIN_PATH_M))[0]
		if len(j) == 0:
			continue
		d = np.linalg.norm(c[j] - c[i], axis=1)
		a = angle_deg(ax[j], ax[i])
		ok = (d <= REVISIT_DIST_M) & (a <= REVISIT_ANGLE_DEG)
		if ok.any():
			has[i] = True
			best[i] = j[ok][np.argmin(d[ok])]
	return has, best


def runs_of(mask):
	out, start = [], None
	for i, m in enumerate(mask):
		if m and start is None:
			start = i
		if not m and start is not None:
			out.append((start, i - 1))
			start = None
	if start is not None:
		out.append((start, len(mask) - 1))
	return out


def score(args):
	with open(os.path.join(args.run, 'report.json')) as f:
		rep = json.load(f)
	ft, kf_at = read_frames(args.run)
	kf_frame = {int(k): i for i, k in enumerate(kf_at) if k >= 0}
	gt_t, gt_c, gt_ax, gt_q = read_tum(args.gt, with_quaternions=True)
	gi = associate(ft, gt_t)
	valid = gi >= 0
	# GT per frame (frames without GT get NaN and never count).
	c = np.full((len(ft), 3), np.nan)
	ax = np.full((len(ft), 3), np.nan)
	qs = np.full((len(ft), 4), np.nan)
	c[valid], ax[valid], qs[valid] = gt_c[gi[valid]], gt_ax[gi[valid]], gt_q[gi[valid]]
	vidx = np.nonzero(valid)[0]
	has_v, best_v = revisits(ft[vidx], c[vidx], ax[vidx])
	has = np.zeros(len(ft), dtype=bool)
	has[vidx] = has_v
	events = runs_of(has)

	dets = []
	warnings = []
	for ev in rep.get('loop_closures', []):
		q = int(ev['frame'])
		kf, lkf = int(ev['keyframe']), int(ev['loop_keyframe'])
		if 'loop_keyframe_timestamp' in ev:  # report.json names the loop keyframe's frame by timestamp
			k = int(np.argmin(np.abs(ft - float(ev['loop_keyframe_timestamp']))))
			lf = k if abs(ft[k] - float(ev['loop_keyframe_timestamp'])) < 1e-3 else -1
		else:
			lf = kf_frame.get(lkf, -1)
		if kf_frame.get(kf, -1) != q:
			warnings.append('loop at frame %d: keyframe %d was created at frame %s' % (q, kf, kf_frame.get(kf)))
		d = {'frame': q, 'keyframe': kf, 'loop_keyframe': lkf, 'loop_frame': lf,
			 'score': ev.get('score'), 'inliers': ev.get('inliers'), 'correction_m': ev.get('correction_m')}
		if lf < 0 or not (valid[q] and valid[lf]):
			d['tp'] = None
			warnings.append('loop at frame %d: no GT for frame %d or %d' % (q, q, lf))
		else:
			d['gt_dist_m'] = float(np.linalg.norm(c[q] - c[lf]))
			d['gt_angle_deg'] = float(angle_deg(ax[q], ax[lf]))
			d['tp'] = bool(d['gt_dist_m'] <= TP_DIST_M and d['gt_angle_deg'] <= TP_ANGLE_DEG)
			if 'measured_distance_m' in ev and 'measured_angle_deg' in ev:
				d['gt_rotation_deg'] = rotation_angle_deg(qs[q], qs[lf])
				d['measured_distance_m'] = float(ev['measured_distance_m'])
				d['measured_angle_deg'] = float(ev['measured_angle_deg'])
				d['constraint_ok'] = bool(abs(d['measured_distance_m'] - d['gt_dist_m']) <= CONSTRAINT_DIST_M and
										  abs(d['measured_angle_deg'] - d['gt_rotation_deg']) <= CONSTRAINT_ANGLE_DEG)
		dets.append(d)

	ev_out = []
	for (a, b) in events:
		hit = [d for d in dets if d['tp'] and ft[a] - EVENT_GRACE_S <= ft[d['frame']] <= ft[b] + EVENT_GRACE_S]
		strict = [d for d in hit if ft[a] <= ft[d['frame']]]
		e = {'start': a, 'end': b, 't_start': float(ft[a] - ft[0]), 't_end': float(ft[b] - ft[0]),
			 'detected': bool(hit), 'detected_strict': bool(strict), 'first_detection': hit[0]['frame'] if hit else None}
		k = int(np.searchsorted(vidx, a))
		e['earlier_frame'] = int(vidx[best_v[k]]) if k < len(vidx) and vidx[k] == a else None
		ev_out.append(e)
	tp = sum(1 for d in dets if d['tp'])
	fp = sum(1 for d in dets if d['tp'] is False)
	wrong = sum(1 for d in dets if d.get('constraint_ok') is False)
	res = {
		'name': args.name or os.path.basename(os.path.normpath(args.run)),
		'mode': args.mode,
		'frames': int(len(ft)),
		'frames_with_gt': int(valid.sum()),
		'keyframes_created': int(rep.get('keyframes_created', -1)),
		'keyframes': int(rep.get('keyframes', -1)),
		'detections': len(dets), 'tp': tp, 'fp': fp, 'wrong_constraints': wrong,
		'precision': (tp / len(dets)) if dets else None,
		'events': len(ev_out), 'events_detected': sum(1 for e in ev_out if e['detected']),
		'recall': (sum(1 for e in ev_out if e['detected']) / len(ev_out)) if ev_out else None,
		'events_detected_strict': sum(1 for e in ev_out if e['detected_strict']),
		'revisit_frames': int(has.sum()),
		'ate_rmse_m': rep.get('ate_rmse_m'),
		'tracked': rep.get('tracked'), 'lost': rep.get('lost'),
		'wall_time_s': rep.get('wall_time_s'),
		'vocab_seconds': args.vocab_seconds,
		'event_list': ev_out, 'detection_list': dets, 'warnings': warnings,
	}
	if args.json:
		with open(args.json, 'w') as f:
			json.dump(res, f, indent=1)
	print(summary_line(res))
	for e in ev_out:
		print('  revisit event frames %d-%d (t %.1f-%.1f s, earlier view: frame %s): %s' % (
			e['start'], e['end'], e['t_start'], e['t_end'], e['earlier_frame'],
			('detected at frame %d' % e['first_detection'] + ('' if e.get('detected_strict', True) else ' (before the event)'))
			if e['detected'] else 'MISSED'))
	for d in dets:
		print('  loop frame %d (kf %d) -> kf %d (frame %d): %s%s%s' % (
			d['frame'], d['keyframe'], d['loop_keyframe'], d['loop_frame'],
			{True: 'TP', False: 'FALSE', None: 'unscored'}[d['tp']],
			' (GT %.2f m, %.1f deg)' % (d['gt_dist_m'], d['gt_angle_deg']) if 'gt_dist_m' in d else '',
			'; constraint %s: measured %.2f m / %.1f deg, GT %.2f m / %.1f deg' % (
				'correct' if d['constraint_ok'] else 'WRONG', d['measured_distance_m'], d['measured_angle_deg'],
				d['gt_dist_m'], d['gt_rotation_deg']) if 'constraint_ok' in d else ''))
	for w in warnings:
		print('  warning: ' + w)


def fmt(v, f='%.3f'):
	return '-' if v is None else f % v


def summary_line(r):
	return '%s [%s]: %d detections, %d TP, %d false, %d wrong constraints, precision %s, recall %d/%d, ATE %s m' % (
		r['name'], r['mode'], r['detections'], r['tp'], r['fp'], r.get('wrong_constraints', 0), fmt(r['precision'], '%.2f'),
		r['events_detected'], r['events'], fmt(r['ate_rmse_m']))


def table(args):
	rs = []
	for p in args.files:
		with open(p) as f:
			rs.append(json.load(f))
	print('| sequence | vocabulary | frames | revisit events (frames) | detections | TP | false | precision | recall | ATE [m] | vocab train [s] | slam wall [s] |')
	print('|---|---|---|---|---|---|---|---|---|---|---|---|')
	for r in rs:
		evs = ', '.join('%d-%d%s' % (e['start'], e['end'], ('' if e.get('detected_strict', True) else ' (TP at %d, before)' % e['first_detection'])
											 if e['detected'] else ' (missed)') for e in r['event_list'])
		print('| %s | %s | %d | %d: %s | %d | %d | %d | %s | %s | %s | %s | %s |' % (
			r['name'], r['mode'], r['frames'], r['events'], evs or '-', r['detections'], r['tp'], r['fp'],
			fmt(r['precision'], '%.2f'), '%d/%d' % (r['events_detected'], r['events']), fmt(r['ate_rmse_m']),
			fmt(r['vocab_seconds'], '%.1f') if r['mode'].startswith('self') else '-', fmt(r['wall_time_s'], '%.0f')))
	print()
	matrix(rs)
	# Totals per vocabulary choice.
	print()
	print('| vocabulary | sequences | detections | TP | false | wrong constraints | precision | recall (events) | strict recall |')
	print('|---|---|---|---|---|---|---|---|---|')
	modes = []
	for r in rs:
		if r['mode'] not in modes:
			modes.append(r['mode'])
	for m in modes:
		sel = [r for r in rs if r['mode'] == m]
		det = sum(r['detections'] for r in sel)
		tp = sum(r['tp'] for r in sel)
		fp = sum(r['fp'] for r in sel)
		ev = sum(r['events'] for r in sel)
		evd = sum(r['events_detected'] for r in sel)
		evs = sum(r.get('events_detected_strict', r['events_detected']) for r in sel)
		wrong = sum(r.get('wrong_constraints', 0) for r in sel)
		print('| %s | %d | %d | %d | %d | %d | %s | %d/%d | %d/%d |' % (m, len(sel), det, tp, fp, wrong, fmt(tp / det if det else None, '%.2f'), evd, ev, evs, ev))


def matrix(rs):
	"""Sequences x vocabularies: 'TP/detections, detected events/events, ATE'."""
	modes, names = [], []
	for r in rs:
		if r['mode'] not in modes:
			modes.append(r['mode'])
		if r['name'] not in names:
			names.append(r['name'])
	by = {(r['name'], r['mode']): r for r in rs}
	print('| sequence (revisit events) | ' + ' | '.join(modes) + ' |')
	print('|---|' + '---|' * len(modes))
	for n in names:
		cells = []
		for m in modes:
			r = by.get((n, m))
			if r is None:
				cells.append('')
				continue
			cells.append('%d/%d TP%s, %d/%d ev, %s m' % (
				r['tp'], r['detections'], ' (%d false)' % r['fp'] if r['fp'] else '', r['events_detected'], r['events'],
				fmt(r['ate_rmse_m'])))
		ev = next(r for r in rs if r['name'] == n)['events']
		print('| %s (%d) | %s |' % (n, ev, ' | '.join(cells)))


def main():
	ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
	sub = ap.add_subparsers(dest='cmd', required=True)
	s = sub.add_parser('score')
	s.add_argument('--run', required=True)
	s.add_argument('--gt', required=True)
	s.add_argument('--name')
	s.add_argument('--mode', default='')
	s.add_argument('--vocab-seconds', type=float, default=None)
	s.add_argument('--json')
	t = sub.add_parser('table')
	t.add_argument('files', nargs='+')
	a = ap.parse_args()
	if a.cmd == 'score':
		score(a)
	else:
		table(a)


if __name__ == '__main__':
	sys.exit(main())
