/*
 * peak_rss COMMAND [ARG...]: runs COMMAND and prints "peak_rss_kb N" (the
 * child's peak resident set, getrusage's ru_maxrss) on stderr; exits with
 * the child's exit code (128 + signal if it was killed).
 *
 * Why a C program: a child's ru_maxrss includes what it inherited from the
 * process that forked it, and a Python test process (about 10 MB) forks
 * children larger than mcsim's whole run. Forked from this small program,
 * the child's peak is mcsim's own (tests/sil/cli/test_mcsim_memory.py).
 */
#define _DEFAULT_SOURCE /* wait4 (glibc: BSD and System V extensions) */
#include <stdio.h>
#include <sys/resource.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

int main(int argc, char** argv) {
  if (argc < 2) {
    fprintf(stderr, "usage: peak_rss COMMAND [ARG...]\n");
    return 2;
  }
  const pid_t pid = fork();
  if (pid < 0) {
    perror("peak_rss: fork");
    return 2;
  }
  if (pid == 0) {
    execvp(argv[1], argv + 1);
    perror("peak_rss: exec");
    _exit(127);
  }
  int status = 0;
  struct rusage ru;
  if (wait4(pid, &status, 0, &ru) != pid) {
    perror("peak_rss: wait4");
    return 2;
  }
  fprintf(stderr, "peak_rss_kb %ld\n", ru.ru_maxrss);
  if (WIFEXITED(status)) {
    return WEXITSTATUS(status);
  }
  return 128 + (WIFSIGNALED(status) ? WTERMSIG(status) : 0);
}
