/* The tet sink; see sink.h. */
#include "front/sink.h"

#include <stdlib.h>
#include <string.h>

int fdt_tsink_init(fdt_tsink *s, const fdt_vid *orig, const fdt_sink *user)
{
    memset(s, 0, sizeof *s);
    s->orig = orig;
    s->user = user;
    s->batch = FDT_SINK_BATCH;
    s->hbatch = FDT_SINK_HBATCH;
    if (pthread_mutex_init(&s->lock, NULL) != 0)
        return FDT_ENOMEM;
    s->lock_ok = 1;
    return FDT_OK;
}

void fdt_tsink_free(fdt_tsink *s)
{
    if (s->lock_ok)
        pthread_mutex_destroy(&s->lock);
    s->lock_ok = 0;
}

int fdt_emit_init(fdt_emit *em, fdt_tsink *s, fdt_meshbuf *mb)
{
    memset(em, 0, sizeof *em);
    em->s = s;
    em->mb = s->user ? NULL : mb;
    em->packed = !(em->mb && em->mb->nbrs);
    if (s->user) {
        if (s->batch < 1 || s->hbatch < 1)
            return FDT_EINVAL;
        em->tb = malloc(s->batch * 4 * sizeof *em->tb);
        em->hb = malloc(s->hbatch * 3 * sizeof *em->hb);
        if (!em->tb || !em->hb) {
            fdt_emit_free(em);
            return FDT_ENOMEM;
        }
    }
    return FDT_OK;
}

void fdt_emit_free(fdt_emit *em)
{
    free(em->tb);
    free(em->hb);
    em->tb = em->hb = NULL;
    em->tn = em->hn = 0;
}

void fdt_sink_renumber(const fdt_vid *orig, fdt_vid *dst, const uint32_t *src, size_t count)
{
    for (size_t i = 0; i < count; i++)
        dst[i] = orig[src[i]];
}

/* Hands the thread's batches to the caller, under the lock (sink.h: the
 * lock serializes the calls and orders each call's writes before the
 * next). A batch is handed on only while no call has asked to stop. */
static int hand_on(fdt_emit *em)
{
    fdt_tsink *s = em->s;
    pthread_mutex_lock(&s->lock);
    int rc = s->rc;
    if (!rc && em->tn) {
        int u = s->user->tets(s->user->user, em->tb, em->tn);
        if (u)
            rc = fdt_sink_code(u);
        else
            s->ntets += em->tn;
    }
    if (!rc && em->hn && s->user->hull) {
        int u = s->user->hull(s->user->user, em->hb, em->hn);
        if (u)
            rc = fdt_sink_code(u);
    }
    if (!rc)
        s->nhull += em->hn;
    if (rc && !s->rc)
        s->rc = rc;
    pthread_mutex_unlock(&s->lock);
    em->tn = em->hn = 0;
    return rc;
}

/* The stream's part of an emission: the tet just written at the batch's
 * end (input numbering) hashed and counted, the batch handed on when
 * full. */
static int64_t stream_tet(fdt_emit *em)
{
    fdt_sethash_add(&em->h, (const uint32_t *)(em->tb + 4 * em->tn));
    if (++em->tn == em->s->batch) {
        int rc = hand_on(em);
        if (rc)
            return rc;
    }
    return em->ntets++;
}

int64_t fdt_emit_tet_any(fdt_emit *em, const uint32_t v[4])
{
    if (em->mb) {
        int64_t tid = fdt_meshbuf_add_tet(em->mb, v);
        if (tid < 0)
            return FDT_ENOMEM;
        em->ntets = tid + 1;
        return tid;
    }
    if (!em->tb)
        return em->ntets++;
    fdt_sink_renumber(em->s->orig, em->tb + 4 * em->tn, v, 4);
    return stream_tet(em);
}

int64_t fdt_emit_tet_known(fdt_emit *em, const uint32_t v[4], const fdt_vid in[4])
{
    if (!em->tb)
        return fdt_emit_tet(em, v);
    memcpy(em->tb + 4 * em->tn, in, 4 * sizeof *in);
    return stream_tet(em);
}

int fdt_emit_hull(fdt_emit *em, const uint32_t f[3])
{
    em->nhull++;
    if (em->mb)
        return fdt_meshbuf_add_hull(em->mb, f);
    if (!em->hb)
        return FDT_OK;
    fdt_sink_renumber(em->s->orig, em->hb + 3 * em->hn, f, 3);
    if (++em->hn == em->s->hbatch)
        return hand_on(em);
    return FDT_OK;
}

int fdt_emit_flush(fdt_emit *em)
{
    fdt_tsink *s = em->s;
    if (!s->user)
        return FDT_OK;
    int rc = hand_on(em);
    pthread_mutex_lock(&s->lock);
    fdt_sethash_merge(&s->hash, &em->h);
    memset(&em->h, 0, sizeof em->h);
    pthread_mutex_unlock(&s->lock);
    return rc;
}
